#pragma once
// Model from a URDF file (parsed by urdfdom). Fixed joints are merged into the parent body's
// inertia; every link (Body frame) and joint (Joint / FixedJoint frame) stays a frame. Joint order:
// depth-first from the root link, sibling joints by name (ARCHITECTURE.md §3). Continuous joints
// are revolute joints without position limits (nq = 1). Mimic tags are ignored: such joints are
// independent. Floating and planar joints inside the tree are refused.

#include <stdexcept>
#include <string>

#include "solver/multibody/model.hpp"

namespace stride {

enum class RootJoint { FreeFlyer, Fixed };

// Loading errors: the message names the file and the offending element.
class UrdfError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The free-flyer root joint is named "root_joint" (as SRDF group_states expect).
Model buildModelFromUrdf(const std::string& path, RootJoint root);
// Same from XML text; `source` names it in error messages.
Model buildModelFromUrdfString(const std::string& xml, RootJoint root,
                               const std::string& source = "<string>");

}  // namespace stride
