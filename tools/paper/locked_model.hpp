#pragma once
// A robot with some joints locked: the paper's astronaut (§V-B) moves only the sagittal hip and
// knee joints. solver/multibody builds models from URDF only, so the reduced model is built by
// rewriting the URDF: every locked joint becomes a fixed joint whose origin carries its rotation at
// the locked angle, and the fixed-joint merge of buildModelFromUrdf folds its child bodies into the
// parent's inertia. The free joints keep their URDF names, axes and limits.

#include <map>
#include <string>
#include <vector>

#include "config/robot_config.hpp"

namespace stride {

// The URDF text of `urdf_path` with every joint named in `locked` turned into a fixed joint at the
// given angle (revolute / continuous joints: rotation about the axis; prismatic: translation along
// it). Throws std::invalid_argument naming a joint that is absent or of another type, UrdfError
// when the file does not parse.
std::string lockJointsInUrdf(const std::string& urdf_path,
                             const std::map<std::string, double>& locked);

struct LockedRobot {
  Model model;                    // free-flyer (as the robot's) + the free joints
  std::vector<std::string> free;  // the free joints, in the reduced model's order
  Eigen::VectorXd default_q;      // the robot's default posture restricted to the free joints
};

// The robot with only `free_joints` moving, every other joint fixed at its default posture angle
// (robot.default_q). Throws std::invalid_argument for an unknown free joint name.
LockedRobot lockJoints(const Robot& robot, const std::vector<std::string>& free_joints);

// The reduced configuration / velocity matching a full one (base and free joints copied).
Eigen::VectorXd reduceConfiguration(const Model& full, const Model& reduced,
                                    const Eigen::VectorXd& q_full);
Eigen::VectorXd reduceVelocity(const Model& full, const Model& reduced,
                               const Eigen::VectorXd& v_full);

// The full robot's configuration / velocity matching a reduced one: base and free joints copied,
// every locked joint at its value in `q_locked` (the angles it was locked at: the robot's
// default_q) and at rest. What a viewer or a log of the full robot needs to show a motion of the
// reduced model (stride-paper-astronaut --log).
Eigen::VectorXd expandConfiguration(const Model& full, const Model& reduced,
                                    const Eigen::VectorXd& q_reduced,
                                    const Eigen::VectorXd& q_locked);
Eigen::VectorXd expandVelocity(const Model& full, const Model& reduced,
                               const Eigen::VectorXd& v_reduced);

}  // namespace stride
