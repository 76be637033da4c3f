#pragma once
// Named reference configurations from an SRDF file's <group_state> entries (e.g. "standing",
// "half_sitting"): each starts from the neutral configuration and sets the listed joints.

#include <string>
#include <vector>

#include "solver/multibody/urdf.hpp"

namespace stride {

struct SrdfReport {
  std::vector<std::string> states;          // names loaded
  std::vector<std::string> ignored_joints;  // joints named in the SRDF that the model lacks
};

// Adds every group_state to model.referenceConfigurations. Joints the model does not have (e.g. a
// reduced model of the SRDF's robot) are skipped and listed in the report; a wrong number of values
// or a non-number is an error. Throws UrdfError naming the file and the element.
SrdfReport loadReferenceConfigurations(Model& model, const std::string& path);

}  // namespace stride
