#include "terrain/terrain_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>

namespace stride::terrain {

namespace {
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw TerrainFileError("terrain file '" + source_ + "': " + key + ": " + what);
  }

  void onlyKeys(const YAML::Node& node, const std::string& where,
                std::initializer_list<const char*> keys) const {
    if (!node.IsMap()) fail(where.empty() ? "(top level)" : where, "expected a map of keys");
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      bool known = false;
      std::string list;
      for (const char* k : keys) {
        known |= key == k;
        list += (list.empty() ? "" : ", ") + std::string(k);
      }
      if (!known)
        fail(where.empty() ? key : where + "." + key, "unknown key (known: " + list + ")");
    }
  }

  double number(const YAML::Node& node, const std::string& key, const char* name,
                bool required = true, double fallback = 0.0) const {
    const YAML::Node v = node[name];
    const std::string where = key + "." + name;
    if (!v) {
      if (required) fail(where, "missing");
      return fallback;
    }
    double x;
    try {
      x = v.as<double>();
    } catch (const YAML::Exception&) {
      fail(where, "expected a number");
    }
    if (!std::isfinite(x)) fail(where, "must be finite");
    return x;
  }
  double positive(const YAML::Node& node, const std::string& key, const char* name) const {
    const double x = number(node, key, name);
    if (!(x > 0.0)) fail(key + "." + name, "must be > 0 (got " + format(x) + ")");
    return x;
  }
  double nonNegative(const YAML::Node& node, const std::string& key, const char* name,
                     bool required) const {
    const double x = number(node, key, name, required);
    if (x < 0.0) fail(key + "." + name, "must be >= 0 (got " + format(x) + ")");
    return x;
  }
  Eigen::Vector2d pair(const YAML::Node& node, const std::string& key, const char* name) const {
    const YAML::Node v = node[name];
    const std::string where = key + "." + name;
    if (!v) fail(where, "missing");
    if (!v.IsSequence() || v.size() != 2) fail(where, "expected [x, y]");
    Eigen::Vector2d out;
    for (int i = 0; i < 2; ++i) {
      try {
        out[i] = v[i].as<double>();
      } catch (const YAML::Exception&) {
        fail(where, "expected [x, y] of numbers");
      }
      if (!std::isfinite(out[i])) fail(where, "must be finite");
    }
    return out;
  }
  // The entries of a list key ("boxes"), each with its index for errors.
  template <typename F>
  void each(const YAML::Node& root, const char* name, F f) const {
    const YAML::Node list = root[name];
    if (!list || list.IsNull()) return;
    if (!list.IsSequence()) fail(name, "expected a list");
    for (std::size_t i = 0; i < list.size(); ++i)
      f(list[i], std::string(name) + "[" + std::to_string(i) + "]");
  }

  static std::string format(double x) {
    std::ostringstream s;
    s << x;
    return s.str();
  }

 private:
  std::string source_;
};
}  // namespace

TerrainSpec parseTerrain(const std::string& text, const std::string& source) {
  const Reader r(source);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    r.fail("(file)", std::string("does not parse: ") + e.what());
  }
  TerrainSpec spec;
  spec.name = std::filesystem::path(source).stem().string();
  if (!root || root.IsNull()) return spec;  // an empty file: the flat ground at 0
  r.onlyKeys(root, "", {"ground", "boxes", "ramps", "stairs", "rough"});
  spec.ground = r.number(root, "", "ground", false, 0.0);
  r.each(root, "boxes", [&](const YAML::Node& n, const std::string& key) {
    r.onlyKeys(n, key, {"center", "size", "height", "yaw"});
    BoxSpec b;
    b.center = r.pair(n, key, "center");
    b.size = r.pair(n, key, "size");
    if (!(b.size.x() > 0.0 && b.size.y() > 0.0))
      r.fail(key + ".size", "must be > 0 (got [" + Reader::format(b.size.x()) + ", " +
                                Reader::format(b.size.y()) + "])");
    b.height = r.number(n, key, "height");
    b.yaw = r.number(n, key, "yaw", false, 0.0);
    spec.boxes.push_back(b);
  });
  r.each(root, "ramps", [&](const YAML::Node& n, const std::string& key) {
    r.onlyKeys(n, key, {"from", "to", "width", "rise"});
    RampSpec ramp;
    ramp.from = r.pair(n, key, "from");
    ramp.to = r.pair(n, key, "to");
    if (!((ramp.to - ramp.from).norm() > 0.0)) r.fail(key + ".to", "must differ from 'from'");
    ramp.width = r.positive(n, key, "width");
    ramp.rise = r.number(n, key, "rise");
    spec.ramps.push_back(ramp);
  });
  r.each(root, "stairs", [&](const YAML::Node& n, const std::string& key) {
    r.onlyKeys(n, key, {"start", "yaw", "steps", "rise", "run", "width", "landing"});
    StairsSpec s;
    s.start = r.pair(n, key, "start");
    s.yaw = r.number(n, key, "yaw", false, 0.0);
    const double steps = r.number(n, key, "steps");
    if (!(steps >= 1.0 && steps <= 1000.0 && steps == std::floor(steps)))
      r.fail(key + ".steps",
             "must be a whole number in [1, 1000] (got " + Reader::format(steps) + ")");
    s.steps = static_cast<int>(steps);
    s.rise = r.number(n, key, "rise");
    s.run = r.positive(n, key, "run");
    s.width = r.positive(n, key, "width");
    s.landing = r.nonNegative(n, key, "landing", false);
    spec.stairs.push_back(s);
  });
  r.each(root, "rough", [&](const YAML::Node& n, const std::string& key) {
    r.onlyKeys(n, key, {"min", "max", "cell", "amplitude", "seed"});
    RoughSpec rough;
    rough.min = r.pair(n, key, "min");
    rough.max = r.pair(n, key, "max");
    if (!(rough.max.array() > rough.min.array()).all())
      r.fail(key + ".max", "must be greater than min in x and y");
    rough.cell = r.positive(n, key, "cell");
    if ((rough.max - rough.min).maxCoeff() / rough.cell > 10000.0)
      r.fail(key + ".cell", "too small: more than 10000 cells along a side");
    rough.amplitude = r.nonNegative(n, key, "amplitude", true);
    const double seed = r.nonNegative(n, key, "seed", false);
    if (seed != std::floor(seed) || seed > 9.0e15) r.fail(key + ".seed", "must be a whole number");
    rough.seed = static_cast<std::uint64_t>(seed);
    spec.rough.push_back(rough);
  });
  return spec;
}

TerrainSpec loadTerrainFile(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw TerrainFileError("terrain file '" + path + "': cannot be read");
  std::stringstream text;
  text << f.rdbuf();
  return parseTerrain(text.str(), path);
}

std::string findTerrainFile(const std::string& name, const std::vector<std::string>& config_dirs) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const bool looks_like_path =
      name.find('/') != std::string::npos || fs::path(name).extension() == ".yaml";
  if (looks_like_path) {
    if (fs::is_regular_file(name, ec)) return name;
    throw TerrainFileError("terrain file '" + name + "': no such file");
  }
  std::string tried;
  for (const std::string& dir : config_dirs) {
    if (dir.empty()) continue;
    const fs::path p = fs::path(dir) / "terrain" / (name + ".yaml");
    if (fs::is_regular_file(p, ec)) return p.string();
    tried += (tried.empty() ? "" : ", ") + p.string();
  }
  throw TerrainFileError("terrain '" + name + "': not found (looked for " + tried + ")");
}

std::vector<std::string> terrainConfigDirs() {
  namespace fs = std::filesystem;
  std::vector<std::string> dirs = {STRIDE_TERRAIN_SOURCE_CONFIG_DIR};
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed =
        (exe.parent_path() / STRIDE_TERRAIN_BIN_TO_DATA / "stride" / "config").lexically_normal();
    if (fs::is_directory(installed, ec)) dirs.push_back(installed.string());
  }
  return dirs;
}

}  // namespace stride::terrain
