#include "viz/server/robot_files.hpp"

#include <tinyxml.h>

#include <filesystem>
#include <stdexcept>

#include "config/package_path.hpp"

namespace stride::viz {

namespace fs = std::filesystem;

namespace {

bool plainChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-';
}

std::string urlName(const std::string& name) {
  // The last component of a path or URI: "package://pkg/meshes/base.stl" -> "base.stl".
  std::string base = name.substr(name.find_last_of('/') + 1);
  for (char& c : base)
    if (!plainChar(c) && c != '.') c = '_';
  if (base.empty() || base[0] == '.') base = "file" + base;  // never "", "." or ".."
  return base;
}

struct Rewriter {
  std::string urdf_dir;
  const std::vector<std::string>& robots_dirs;
  RobotFiles& out;

  int indexOf(const std::string& name) {
    for (std::size_t i = 0; i < out.files.size(); ++i)
      if (out.files[i].name == name) return static_cast<int>(i);
    RobotFile file{name, urlName(name), ""};
    try {
      file.path = resolveRobotFile(name, urdf_dir, robots_dirs);
    } catch (const std::exception& e) {
      out.missing.push_back(e.what());
    }
    out.files.push_back(file);
    return static_cast<int>(out.files.size()) - 1;
  }

  void visit(TiXmlElement* element) {
    for (; element != nullptr; element = element->NextSiblingElement()) {
      if (const char* name = element->Attribute("filename")) {
        const int index = indexOf(name);
        element->SetAttribute("filename", robotFileUrl(index, out.files[index]).c_str());
      }
      visit(element->FirstChildElement());
    }
  }
};

}  // namespace

std::string robotFileUrl(int index, const RobotFile& file) {
  return "/robot/files/" + std::to_string(index) + "/" + file.url_name;
}

RobotFiles rewriteUrdf(const std::string& urdf_path, const std::vector<std::string>& robots_dirs) {
  TiXmlDocument doc(urdf_path);
  if (!doc.LoadFile())
    throw std::runtime_error("URDF '" + urdf_path + "': " + doc.ErrorDesc() + " (line " +
                             std::to_string(doc.ErrorRow()) + ")");
  RobotFiles out;
  Rewriter rewriter{fs::path(urdf_path).parent_path().string(), robots_dirs, out};
  rewriter.visit(doc.RootElement());
  TiXmlPrinter printer;
  printer.SetIndent("  ");
  doc.Accept(&printer);
  out.urdf = printer.Str();
  return out;
}

std::string findRobotYaml(const std::string& name, const std::vector<std::string>& config_dirs,
                          std::vector<std::string>* tried) {
  if (name.empty() || name.size() > 64) return "";
  for (const char c : name)
    if (!plainChar(c)) return "";
  for (const std::string& dir : config_dirs) {
    if (dir.empty()) continue;
    const fs::path yaml = fs::path(dir) / "robots" / name / (name + ".yaml");
    if (tried) tried->push_back(yaml.string());
    std::error_code ec;
    if (fs::is_regular_file(yaml, ec)) return yaml.string();
  }
  return "";
}

}  // namespace stride::viz
