#include "config/describe_model.hpp"

#include "config/model_hash.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <sstream>

namespace stride {

namespace {
// "q[7]" for one coordinate, "q[0:7]" (half-open, as the indices are used) for several.
std::string range(char vec, int start, int n) {
  std::string s = std::string(1, vec) + "[" + std::to_string(start);
  if (n != 1) s += ":" + std::to_string(start + n);
  return s + "]";
}

bool prismatic(const Joint& j) {
  return j.type == JointType::Prismatic;
}
}  // namespace

std::string describeModel(const Robot& robot) {
  const Model& model = robot.model;
  const bool ff = model.hasFreeFlyer();
  const int nu = actuatedDimension(model);
  std::size_t w = 0;  // name column width
  for (const Joint& j : model.joints) w = std::max(w, j.name.size());
  for (const auto& c : robot.contacts) w = std::max(w, c.frame.size());

  std::ostringstream out;
  out << std::fixed;
  out << "robot " << robot.name << "\n  yaml  " << robot.yaml_path << "\n  urdf  "
      << robot.urdf_path << "\n";
  if (!robot.srdf_path.empty()) {
    out << "  srdf  " << robot.srdf_path;
    if (!robot.reference_posture.empty())
      out << " (default posture from group_state '" << robot.reference_posture << "')";
    out << "\n";
  }
  out << "nq " << model.nq << ", nv " << model.nv << ", nu " << nu << "; total mass "
      << std::setprecision(3) << model.totalMass() << " kg";
  if (ff)
    out << "; base height " << std::setprecision(4) << robot.default_q[2]
        << " m in the default posture";
  out << (ff ? "" : "; fixed base") << "\n";
  char hash[17];
  std::uint64_t h;
  const std::int64_t signed_hash = modelHash(robot);
  std::memcpy(&h, &signed_hash, 8);
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(h));
  out << "model hash " << hash << " (int64 " << signed_hash
      << "; of the joint names, types and order, the contact frames and the kinematic tree's "
         "geometry): every robot_state_t "
         "and policy_t carries it in model_hash\n";

  auto row = [&](const std::string& index, const std::string& name, const std::string& what) {
    out << "  " << std::left << std::setw(8) << index << " ";
    if (what.empty())
      out << name;
    else
      out << std::setw(static_cast<int>(w)) << name << "  " << what;
    out << std::right << "\n";
  };
  out << "q, configuration (" << model.nq << "):\n";
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    row(range('q', j.idx_q, j.nq), j.name,
        j.type == JointType::FreeFlyer ? "free-flyer: x y z qx qy qz qw (world frame)" : "");
  }
  out << "v, velocity (" << model.nv << "):\n";
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    row(range('v', j.idx_v, j.nv), j.name,
        j.type == JointType::FreeFlyer ? "base linear, angular velocity (base frame)" : "");
  }
  out << "u, joint torques (" << nu << "):\n";
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    if (j.type == JointType::FreeFlyer) continue;
    row(range('u', j.idx_v - (ff ? 6 : 0), j.nv), j.name, "");
  }
  out << "contacts (" << robot.contacts.size() << "):\n";
  for (std::size_t k = 0; k < robot.contacts.size(); ++k) {
    const ContactSpec& c = robot.contacts[k];
    std::ostringstream what;
    what << std::fixed << "dim " << c.dim;
    if (c.dim == 3) what << " (point)";
    if (c.dim == 6) {
      what << " (surface";
      if (robot.sole_half_extents.x() > 0)
        what << std::setprecision(3) << ", sole half extents " << robot.sole_half_extents.x()
             << " x " << robot.sole_half_extents.y() << " m";
      what << ")";
    }
    row("[" + std::to_string(k) + "]", c.frame, what.str());
  }
  out << "actuated joints (torque limit, default position):\n";
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    if (j.type == JointType::FreeFlyer) continue;
    std::ostringstream what;
    what << std::fixed << std::setprecision(2) << std::setw(8) << model.effortLimit[j.idx_v]
         << (prismatic(j) ? " N  " : " N m") << std::setprecision(4) << std::setw(10)
         << robot.default_q[j.idx_q] << (prismatic(j) ? " m" : " rad");
    row(range('u', j.idx_v - (ff ? 6 : 0), j.nv), j.name, what.str());
  }
  return out.str();
}

}  // namespace stride
