#include "config/package_path.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

namespace stride {

namespace fs = std::filesystem;

namespace {

bool startsWith(const std::string& s, const char* prefix) {
  return s.rfind(prefix, 0) == 0;
}

// ROS_PACKAGE_PATH's entries; empty entries (a leading, trailing or doubled ':') name nothing.
std::vector<std::string> rosPackagePath() {
  std::vector<std::string> dirs;
  const char* env = std::getenv("ROS_PACKAGE_PATH");
  if (!env) return dirs;
  const std::string s = env;
  for (std::size_t begin = 0; begin <= s.size();) {
    const std::size_t end = std::min(s.find(':', begin), s.size());
    if (end > begin) dirs.push_back(s.substr(begin, end - begin));
    begin = end + 1;
  }
  return dirs;
}

// The candidates of one directory, in the documented order.
std::vector<fs::path> candidates(const fs::path& dir, const std::string& name,
                                 const std::string& rest) {
  std::vector<fs::path> out{dir / name / rest};
  // "pkg/" and "pkg" are the same package directory.
  fs::path self = dir.lexically_normal();
  if (!self.has_filename()) self = self.parent_path();
  if (self.filename() == name) out.push_back(dir / rest);
  out.push_back(dir / "share" / name / rest);
  return out;
}

std::string resolvePackage(const std::string& uri, const std::vector<std::string>& robots_dirs) {
  const std::string body = uri.substr(std::string("package://").size());
  const std::size_t slash = body.find('/');
  if (slash == 0 || slash == std::string::npos || slash + 1 == body.size())
    throw ConfigError("'" + uri + "' is not of the form package://NAME/PATH");
  const std::string name = body.substr(0, slash), rest = body.substr(slash + 1);

  std::vector<std::string> dirs;  // an empty entry would look in the working directory
  for (const auto& d : robots_dirs)
    if (!d.empty()) dirs.push_back(d);
  for (auto& d : rosPackagePath()) dirs.push_back(d);
  std::vector<std::string> tried;
  for (const auto& d : dirs)
    for (const fs::path& p : candidates(d, name, rest)) {
      tried.push_back(p.string());
      if (fs::is_regular_file(p)) return p.string();
    }

  std::string what = "cannot find '" + uri + "' (add the directory that holds package '" + name +
                     "' to ROS_PACKAGE_PATH, colon-separated, or pass it with --robots-dir)";
  if (tried.empty()) {
    what += ": no directory to look in";
  } else {
    what += "; looked at:";
    for (const auto& t : tried) what += "\n  " + t;
  }
  throw RobotFileNotFound(what, tried);
}

}  // namespace

std::string resolveRobotFile(const std::string& uri_or_path, const std::string& relative_to_dir,
                             const std::vector<std::string>& robots_dirs) {
  if (startsWith(uri_or_path, "package://")) return resolvePackage(uri_or_path, robots_dirs);
  std::string path = uri_or_path;
  if (startsWith(path, "file://")) path = path.substr(std::string("file://").size());
  if (path.empty()) throw ConfigError("empty file name");
  const fs::path p =
      fs::path(path).is_absolute() ? fs::path(path) : relative_to_dir / fs::path(path);
  if (!fs::is_regular_file(p))
    throw RobotFileNotFound("'" + uri_or_path + "' (" + p.string() + ") does not exist",
                            {p.string()});
  return p.string();
}

}  // namespace stride
