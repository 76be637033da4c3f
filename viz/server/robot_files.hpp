#pragma once
// What the page needs to draw the robot, and nothing more: the URDF with every file it names
// (meshes, textures) replaced by a URL the server answers, `/robot/files/<index>/<basename>`, and
// the table from index to the file on disk. The page never sends a path that reaches the file
// system: it can only ask for an index the table holds, under that file's own basename.
// Also where a robot named on the wire (robot_model_t.robot) has its YAML.

#include <string>
#include <vector>

namespace stride::viz {

struct RobotFile {
  std::string name;      // as the URDF named it (package://..., relative or absolute)
  std::string url_name;  // the basename the URL carries ([A-Za-z0-9._-], others as '_')
  std::string path;      // resolved; empty when the file could not be found (its URL answers 404)
};

struct RobotFiles {
  std::string urdf;  // the rewritten URDF text
  std::vector<RobotFile> files;
  std::vector<std::string> missing;  // why each unresolved file was not found, one line each
};

// Reads the URDF at `urdf_path` and rewrites every `filename` attribute (<mesh>, <texture>, any
// element): package:// URIs resolved through `robots_dirs` then ROS_PACKAGE_PATH
// (config/package_path.hpp), other names against the URDF's folder. A file named twice gets one
// index. Throws std::runtime_error when the URDF cannot be read or parsed.
RobotFiles rewriteUrdf(const std::string& urdf_path, const std::vector<std::string>& robots_dirs);

// The URL of file `index` ("/robot/files/3/base.stl").
std::string robotFileUrl(int index, const RobotFile& file);

// `<dir>/robots/<name>/<name>.yaml` in the first of `config_dirs` that has it, else "" (with
// every path looked at in `tried`). A name from the wire is not trusted: one that is not a plain
// file name ([A-Za-z0-9_-], at most 64 characters) finds nothing.
std::string findRobotYaml(const std::string& name, const std::vector<std::string>& config_dirs,
                          std::vector<std::string>* tried = nullptr);

}  // namespace stride::viz
