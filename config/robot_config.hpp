#pragma once
// A robot we run: its URDF model plus what the URDF cannot say (config/robots/<name>/<name>.yaml):
// contact frames and their dimension, torque limits and the default posture. YAML lives here, not
// in solver/, which knows nothing of file formats beyond URDF/SRDF (ARCHITECTURE.md §2).

#include <string>
#include <vector>

#include "config/config_error.hpp"
#include "solver/multibody/model.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {

struct ContactSpec {
  std::string frame;
  int dim = 3;  // 3: point contact, 6: surface contact
};

struct Robot {
  Model model;
  std::string name;
  std::string yaml_path;
  std::string urdf_path;
  std::vector<ContactSpec> contacts;
  Eigen::VectorXd default_q;  // also model.referenceConfigurations["default"]
  Eigen::Vector2d sole_half_extents = Eigen::Vector2d::Zero();  // surface contacts, if given
};

// Loads the YAML and its URDF; torque limits replace the URDF efforts. Every error names the file
// and the key (ConfigError) or the URDF element (UrdfError).
Robot loadRobot(const std::string& yaml_path);

}  // namespace stride
