#pragma once
// Where a robot file named in a YAML lives. Users keep their robot descriptions where ROS and the
// robot's publisher put them (e.g. example-robot-data), and name them the way URDFs and launch
// files do: `package://NAME/REST`. Plain paths are taken relative to the YAML that names them.

#include <string>
#include <utility>
#include <vector>

#include "config/config_error.hpp"

namespace stride {

// A file that is not where its name says. `tried()` lists every candidate path, in the order they
// were looked at, so a program or a test can show or check them.
class RobotFileNotFound : public ConfigError {
 public:
  RobotFileNotFound(const std::string& what, std::vector<std::string> tried)
      : ConfigError(what), tried_(std::move(tried)) {}
  const std::vector<std::string>& tried() const { return tried_; }

 private:
  std::vector<std::string> tried_;
};

// The path of an existing file named by `uri_or_path`:
// - `package://NAME/REST`: for each directory D of `robots_dirs` (e.g. `--robots-dir`), then of the
//   ROS_PACKAGE_PATH environment variable (colon-separated), the first existing of D/NAME/REST,
//   D/REST (only when D's last component is NAME: D is the package itself) and D/share/NAME/REST
//   (an install prefix);
// - `file://PATH`, or PATH: an absolute path, or one relative to `relative_to_dir`.
// Throws RobotFileNotFound naming the URI and every place looked, and ConfigError for a malformed
// URI. The message does not name the YAML: the caller adds it.
std::string resolveRobotFile(const std::string& uri_or_path, const std::string& relative_to_dir,
                             const std::vector<std::string>& robots_dirs);

}  // namespace stride
