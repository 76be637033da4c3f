#pragma once
// stride-init's setup of a new robot (issue 34, "Bring your own robot"; tools/init/README.md): from
// a URDF and an SRDF, the robot YAML, a controller YAML from the shipped template of its size and a
// command script. Everything here is plain computation and file writing; the drive and the report
// card are init_main.cpp's.

#include <Eigen/Core>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace stride::init {

// Bad input (a file, a foot, a placeholder effort, a posture): stride-init exits 2 with it.
class InitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct InitInput {
  std::string urdf_uri, srdf_uri;  // as given (paths or package://)
  std::string posture;             // empty: standing, half_sitting or straight_standing
  std::string name;                // empty: the URDF's robot name
  std::vector<std::string> feet;   // empty: the SRDF's end effectors
  bool sole_given = false;
  Eigen::Vector2d sole_half_extents = Eigen::Vector2d::Zero();
  double torque_limit = 0.0;  // > 0: every actuated joint
  // --lock NAME[=VALUE]: joints held (grippers, a head), at VALUE or 0. The leaders of the URDF's
  // <mimic> joints are locked at 0 unless given: Stride has no coupled joints.
  std::map<std::string, double> locked;
  std::vector<std::string> robots_dirs;
  std::string out_dir;
  std::string config_dir;  // the shipped config/ (controller templates)
};

struct Foot {
  std::string frame;
  int dim = 3;
  Eigen::Vector3d in_base = Eigen::Vector3d::Zero();  // at the posture
};

// What was decided, for the files and the report card.
struct Setup {
  std::string name, urdf_path, srdf_path;
  std::string urdf_entry, srdf_entry;  // what the robot YAML says (URIs kept, paths absolute)
  std::string posture;
  std::vector<Foot> feet;  // in the gaits' order
  Eigen::Vector2d sole_half_extents = Eigen::Vector2d::Zero();
  double mass = 0.0, leg_length = 0.0;
  Eigen::Matrix<double, 7, 1> base;  // the posture's base, on the ground
  int nq = 0, nv = 0, nu = 0;
  double com_outside = 0.0;  // [m] at the posture as written (negative: inside)
  std::map<std::string, double> corrected_joints;  // empty: the SRDF state as it is
  std::map<std::string, double> locked;            // the robot YAML's locked_joints
  std::vector<std::string> notes;                  // printed: decisions and corrections
  std::string template_name;                       // e.g. "solo12"
  double ratio = 1.0;                              // sqrt(leg length / template's)
  double mass_ratio = 1.0;                         // mass / template's
  double forward_speed = 0.0, turn_rate = 0.0;     // the command script's
  std::string gait;                                // trot (4 feet) or walk (2)
  double joint_kp = 0.0, joint_kd = 0.0;           // the robot YAML's joint_pd (0: none)
  int policy_knots = 0;
};

// Reads and checks the URDF and SRDF, orders the feet, checks (and for a biped corrects) the
// posture, picks the template. Throws InitError.
Setup analyse(const InitInput& in);

// The three files' paths in out_dir.
std::vector<std::string> outputFiles(const InitInput& in, const std::string& name);

// Writes N.yaml, N_controller.yaml and N_commands.yaml (the caller checked --force).
void writeFiles(const InitInput& in, Setup& setup);

}  // namespace stride::init
