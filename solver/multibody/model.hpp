#pragma once
// The immutable description of a robot: a kinematic tree of joints carrying rigid bodies, plus
// named frames. Built once (from URDF or in code), then only read; every algorithm writes into a
// separate Data workspace (data.hpp). Conventions: ARCHITECTURE.md §3.

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver/multibody/spatial.hpp"

namespace stride {

// The joints we support. Fixed URDF joints do not appear here: their bodies are merged into the
// parent joint's inertia and they stay reachable as frames.
enum class JointType : std::uint8_t {
  Universe,   // joint 0, the fixed world
  FreeFlyer,  // SE(3) root: q = [x y z qx qy qz qw], v = [linear; angular] in the base frame
  Revolute,   // one rotation about `axis` (URDF revolute and continuous)
  Prismatic,  // one translation along `axis`
};

const char* toString(JointType type);

struct Joint {
  std::string name;
  JointType type = JointType::Universe;
  int parent = -1;  // parent joint index (0 = universe)
  SE3 placement;    // parent joint frame -> this joint frame at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit axis, in this joint's frame
  // 0, 1, 2 when the axis is +x, +y, +z: the elementary rotation is then cheaper to build.
  int alignedAxis = -1;
  int idx_q = 0, idx_v = 0, nq = 0, nv = 0;
};

enum class FrameType : std::uint8_t { Joint, FixedJoint, Body, Operational };
const char* toString(FrameType type);

struct Frame {
  std::string name;
  FrameType type = FrameType::Operational;
  int parentJoint = 0;  // the moving joint that carries this frame
  int parentFrame = 0;  // the frame it was attached to in the description (tree of frames)
  SE3 placement;        // in the parent joint's frame
};

// Reference frame in which a frame velocity, acceleration or Jacobian is expressed.
enum class ReferenceFrame : std::uint8_t {
  Local,              // the frame's own axes and origin
  World,              // world axes, velocity of the point at the world origin
  LocalWorldAligned,  // world axes, velocity of the frame's origin
};

class Model {
 public:
  std::string name;
  int nq = 0;
  int nv = 0;
  std::vector<Joint> joints;      // joints[0] is the universe
  std::vector<Inertia> inertias;  // body inertia carried by each joint, in its frame
  std::vector<Frame> frames;      // frames[0] is "universe"
  // For each velocity index k: the velocity index just above it on the path to the root
  // (the previous dof of the same joint, else the last dof of the parent joint), -1 at the root.
  // Walking it visits exactly the dofs that support k: Jacobians and CRBA use it.
  std::vector<int> parentDof;
  // For each velocity index k: the number of dofs in the subtree it moves, itself included.
  // Depth-first order makes that subtree the contiguous range [k, k + nvSubtree[k]).
  std::vector<int> nvSubtree;
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.81);

  // Joint limits, in configuration / velocity indices (+-inf when the description has none).
  Eigen::VectorXd lowerPositionLimit, upperPositionLimit, velocityLimit, effortLimit;
  // Named configurations, e.g. "standing" from an SRDF group_state (srdf.hpp).
  std::map<std::string, Eigen::VectorXd> referenceConfigurations;

  Model();

  int njoints() const { return static_cast<int>(joints.size()); }
  int nframes() const { return static_cast<int>(frames.size()); }
  bool hasFreeFlyer() const { return njoints() > 1 && joints[1].type == JointType::FreeFlyer; }

  // ---- building (used by the URDF parser, tests and random trees) ----
  // Adds a moving joint below `parent` and a frame of type Joint with its name; returns its index.
  // Joints are added in depth-first order: `parent` is the universe, the last joint added or one of
  // its ancestors. A free-flyer may only be attached to the universe. Throws std::invalid_argument.
  int addJoint(int parent, JointType type, const SE3& placement, const std::string& name,
               const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ());
  void setJointLimits(int joint, double lower, double upper, double velocity, double effort);
  // Adds a body with inertia Y (expressed in `placement`'s frame) rigidly to a joint.
  void appendBodyToJoint(int joint, const Inertia& Y, const SE3& placement = SE3::Identity());
  // Adds a frame; returns its index. A name may be shared only by frames of different types (a link
  // and a joint of the same name, as some URDFs have). Throws std::invalid_argument.
  int addFrame(const Frame& frame);

  // ---- lookup ----
  bool existJoint(const std::string& joint_name) const;
  bool existFrame(const std::string& frame_name) const;
  int getJointId(const std::string& joint_name) const;  // throws std::out_of_range naming it
  // The first frame added with that name (ask by type when names are shared); throws
  // std::out_of_range naming it.
  int getFrameId(const std::string& frame_name) const;
  int getFrameId(const std::string& frame_name, FrameType type) const;
  // Total mass of the moving bodies (the universe's fixed bodies carry no dynamics).
  double totalMass() const;
  // Mass rigidly attached to the universe (fixed-base robots: the base itself).
  double fixedMass() const { return inertias[0].m; }

  // ---- API boundary checks: throw std::invalid_argument naming the argument and sizes ----
  void checkConfiguration(const Eigen::Ref<const Eigen::VectorXd>& q, const char* what) const;
  void checkVelocity(const Eigen::Ref<const Eigen::VectorXd>& v, const char* what) const;

 private:
  std::map<std::string, int> frame_index_;
  std::map<std::string, int> joint_index_;
};

// The number of actuated degrees of freedom: the size of a control u and of a policy's torques. A
// floating base is unactuated, τ = [0_6; u]; a fixed base is fully actuated, τ = u. Every 1-dof
// joint below the base is actuated (the convention of the knots, the policy on the wire and the
// mock robot). A property of the model, not of the contact dynamics that first needed it.
int actuatedDimension(const Model& model);

// Thrown for wrong sizes at an algorithm's boundary: a programming error, never raised on a
// correctly sized real-time call.
[[noreturn]] void throwSizeError(const char* function, const char* argument, long expected,
                                 long got);

}  // namespace stride
