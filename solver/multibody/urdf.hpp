#pragma once
// Model from a URDF file (parsed by urdfdom). Fixed joints are merged into the parent body's
// inertia; every link (Body frame) and joint (Joint / FixedJoint frame) stays a frame. Joint order:
// depth-first from the root link, sibling joints by name (ARCHITECTURE.md §3). Continuous joints
// are revolute joints without position limits (nq = 1). Floating and planar joints inside the tree
// are refused.
//
// Locked joints: a revolute / continuous / prismatic joint named in `locked_joints` becomes a fixed
// joint whose placement includes its motion at the given angle (rotation about its axis, or
// translation along it): its child bodies merge into the parent's inertia, and its frame is a
// FixedJoint frame (it owns no coordinate). The angle must be finite and within the joint's limits.
// Mimic joints (a moving joint with a <mimic joint="L" multiplier="m" offset="o"/> tag) load one
// of two ways (MimicJoints). For dynamics alone (the builders without locked joints:
// stride-check-dynamics, the benchmarks) each is an independent joint with its own coordinate, as
// the usual URDF parsers load them: the tree as drawn, its coupling not modelled. For control
// (the builders with locked joints: the robot loader, stride-init) Stride has no coupled joints,
// so a mimic is locked at m * angle(L) + o when its leader L is locked (a fixed leader counts as
// locked at 0; chains of mimics follow), and the model is refused (UrdfError listing every such
// joint) when L is free. A <mimic> tag on a fixed joint owns nothing and is ignored
// (talos_reduced's gripper fingers).

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver/multibody/model.hpp"

namespace stride {

enum class RootJoint { FreeFlyer, Fixed };

// Loading errors: the message names the file and the offending element.
class UrdfError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A moving joint that copies another: q = multiplier * q(leader) + offset.
struct MimicJoint {
  std::string name;
  std::string leader;
  double multiplier = 1.0;
  double offset = 0.0;
};

// How moving <mimic> joints load (above).
enum class MimicJoints {
  Independent,        // each its own joint (dynamics alone)
  FollowLockedLeader  // locked with its locked leader, refused when the leader is free (control)
};

// The free-flyer root joint is named "root_joint" (as SRDF group_states expect). No joint locked,
// and mimic joints as independent joints (MimicJoints::Independent; urdfMimicJoints lists them).
Model buildModelFromUrdf(const std::string& path, RootJoint root);
// With the joints of `locked_joints` (name -> angle [rad] or position [m]) locked, and their mimic
// joints with them (MimicJoints::FollowLockedLeader, even for an empty map: a free mimic is
// refused). A name that is not a moving joint of the URDF (absent, fixed, the root) or an angle
// that is not finite or outside the joint's limits is a UrdfError naming it.
Model buildModelFromUrdf(const std::string& path, RootJoint root,
                         const std::map<std::string, double>& locked_joints);
// Same from XML text; `source` names it in error messages. (A bare `{}` as third argument is
// ambiguous between `source` and `locked_joints`: pass a named map.)
Model buildModelFromUrdfString(const std::string& xml, RootJoint root,
                               const std::string& source = "<string>");
Model buildModelFromUrdfString(const std::string& xml, RootJoint root,
                               const std::map<std::string, double>& locked_joints,
                               const std::string& source = "<string>");

// The URDF's moving mimic joints, in file order (mimic tags on fixed joints are not listed): the
// leaders to put in `locked_joints`. Throws UrdfError as the builders do for a bad file or a
// <mimic> tag naming no joint.
std::vector<MimicJoint> urdfMimicJoints(const std::string& path);
std::vector<MimicJoint> urdfMimicJointsFromString(const std::string& xml,
                                                  const std::string& source = "<string>");

}  // namespace stride
