#include "controller/command_script.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "config/robot_config.hpp"

namespace stride {

std::vector<ScriptedCommand> loadCommandScript(const std::string& path) {
  auto fail = [&](const std::string& what) {
    throw ConfigError("command script '" + path + "': " + what);
  };
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    fail("file does not exist or cannot be read");
  } catch (const YAML::Exception& e) {
    fail(std::string("malformed YAML: ") + e.what());
  }
  if (!root.IsSequence() || root.size() == 0)
    fail("must be a non-empty list of {at, vx, vy, yaw_rate, gait, body_height, jump}");
  static const std::set<std::string> keys = {"at",   "vx",          "vy",  "yaw_rate",
                                             "gait", "body_height", "jump"};
  std::vector<ScriptedCommand> script;
  ScriptedCommand c;
  for (std::size_t i = 0; i < root.size(); ++i) {
    const YAML::Node e = root[i];
    const std::string where = "entry " + std::to_string(i);
    if (!e.IsMap()) fail(where + ": must be a mapping");
    for (const auto& kv : e)
      if (!keys.count(kv.first.as<std::string>()))
        fail(where + ": unknown key '" + kv.first.as<std::string>() + "'");
    if (!e["at"]) fail(where + ": missing key 'at'");
    auto number = [&](const char* key, double& out) {
      if (!e[key]) return;
      try {
        out = e[key].as<double>();
      } catch (const YAML::Exception&) {
        fail(where + ": " + key + " must be a number");
      }
      if (!std::isfinite(out)) fail(where + ": " + key + " must be finite");
    };
    number("at", c.at);
    number("vx", c.vx);
    number("vy", c.vy);
    number("yaw_rate", c.yaw_rate);
    number("body_height", c.body_height);
    if (e["gait"]) {
      try {
        c.gait = e["gait"].as<std::string>();
      } catch (const YAML::Exception&) {
        fail(where + ": gait must be a string");
      }
    }
    // A jump is the entry's own.
    c.jump_id = 0;
    c.jump = JumpTarget{};
    if (const YAML::Node j = e["jump"]) {
      if (!j.IsMap()) fail(where + ": jump must be a mapping {dx, dy, dz, yaw}");
      for (const auto& kv : j) {
        const std::string key = kv.first.as<std::string>();
        double* field = key == "dx"    ? &c.jump.dx
                        : key == "dy"  ? &c.jump.dy
                        : key == "dz"  ? &c.jump.dz
                        : key == "yaw" ? &c.jump.yaw
                                       : nullptr;
        if (!field) fail(where + ": jump: unknown key '" + key + "' (known: dx, dy, dz, yaw)");
        try {
          *field = kv.second.as<double>();
        } catch (const YAML::Exception&) {
          fail(where + ": jump." + key + " must be a number");
        }
        if (!std::isfinite(*field)) fail(where + ": jump." + key + " must be finite");
      }
      c.jump_id = static_cast<int>(i) + 1;
    }
    if (c.at < 0.0) fail(where + ": at must be non-negative");
    if (!script.empty() && !(c.at > script.back().at))
      fail(where + ": at must be later than the previous entry's");
    script.push_back(c);
  }
  return script;
}

command_t toCommand(const ScriptedCommand& c, std::int64_t utime) {
  command_t m{};
  m.utime = utime;
  m.vx = c.vx;
  m.vy = c.vy;
  m.yaw_rate = c.yaw_rate;
  m.gait = c.gait;
  m.body_height = c.body_height;
  m.jump_id = c.jump_id;
  m.jump[0] = c.jump.dx;
  m.jump[1] = c.jump.dy;
  m.jump[2] = c.jump.dz;
  m.jump[3] = c.jump.yaw;
  return m;
}

int commandAt(const std::vector<ScriptedCommand>& script, double t) {
  int i = 0;
  while (i + 1 < static_cast<int>(script.size()) && script[i + 1].at <= t) ++i;
  return i;
}

void checkScriptGaits(const std::vector<ScriptedCommand>& script, const std::string& path,
                      const std::vector<std::string>& gaits, const std::string& what) {
  for (std::size_t i = 0; i < script.size(); ++i) {
    const std::string& g = script[i].gait;
    if (g.empty() || std::find(gaits.begin(), gaits.end(), g) != gaits.end()) continue;  // "": keep
    std::string list;
    for (const std::string& n : gaits) list += (list.empty() ? "" : ", ") + n;
    std::ostringstream at;
    at << script[i].at;
    throw ConfigError("command script '" + path + "': entry " + std::to_string(i) + " (at " +
                      at.str() + " s): gait '" + g + "': " + what + " walks with " + list +
                      " only");
  }
}

}  // namespace stride
