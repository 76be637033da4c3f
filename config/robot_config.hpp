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
  std::string urdf_path;          // resolved (package:// URIs become paths)
  std::string srdf_path;          // empty without an `srdf:` key
  std::string reference_posture;  // the SRDF group_state the default posture starts from, if any
  std::vector<ContactSpec> contacts;
  // Also model.referenceConfigurations["default"]. For a free-flyer, the base height puts the
  // lowest contact frame at z = 0 exactly, whatever the YAML or SRDF said.
  Eigen::VectorXd default_q;
  Eigen::Vector2d sole_half_extents = Eigen::Vector2d::Zero();  // surface contacts, if given
  // The robot's own joint PD (YAML `joint_pd: {kp, kd}`): what its low level does without a
  // controller (the mock robot before the first policy and when it stands down, sim/README.md).
  // Zero when the YAML does not give it.
  double joint_kp = 0.0, joint_kd = 0.0;
};

// Loads the YAML, its URDF and its SRDF (if any). `robots_dirs` (e.g. the programs' repeatable
// `--robots-dir`) are searched for `package://` URIs before ROS_PACKAGE_PATH (package_path.hpp).
// Torque limits given in the YAML replace the URDF efforts. Every error names the file and the key
// (ConfigError; RobotFileNotFound for a file that cannot be found) or the URDF/SRDF element
// (wrapped UrdfError). Writes a warning to stderr when the given base height misses the ground
// by more than 1 mm.
// Refuses what would run but mean something else (issue 34): contacts not in the order the gaits
// assume (four feet: front-left, front-right, hind-left, hind-right; two: left, right; judged by
// their positions in the base frame at the default posture), a moving joint's frame as a contact,
// dim 6 without sole_half_extents, and a default posture whose centre of mass is more than 5 cm
// outside the support polygon (beyond 5 mm: a warning with the distance).
Robot loadRobot(const std::string& yaml_path, const std::vector<std::string>& robots_dirs = {});

// The signed distance [m] from the ground projection of the centre of mass at q to the support
// polygon of the contacts (point feet, the soles' corners): negative inside, by the distance to
// the nearest edge; positive outside (for two point feet the polygon is the segment between
// them). A fixed-base robot or one without contacts: -infinity.
double comOutsideSupport(const Robot& robot, const Eigen::VectorXd& q);

}  // namespace stride
