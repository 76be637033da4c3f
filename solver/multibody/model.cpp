#include "solver/multibody/model.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace stride {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

void appendRows(Eigen::VectorXd& v, int n, double value) {
  const Eigen::Index old = v.size();
  v.conservativeResize(old + n);
  v.tail(n).setConstant(value);
}
}  // namespace

const char* toString(JointType type) {
  switch (type) {
    case JointType::Universe:
      return "universe";
    case JointType::FreeFlyer:
      return "free-flyer";
    case JointType::Revolute:
      return "revolute";
    case JointType::Prismatic:
      return "prismatic";
  }
  return "?";
}

const char* toString(FrameType type) {
  switch (type) {
    case FrameType::Joint:
      return "joint";
    case FrameType::FixedJoint:
      return "fixed joint";
    case FrameType::Body:
      return "body";
    case FrameType::Operational:
      return "operational";
  }
  return "?";
}

int actuatedDimension(const Model& model) {
  return model.hasFreeFlyer() ? model.nv - 6 : model.nv;
}

void throwSizeError(const char* function, const char* argument, long expected, long got) {
  std::ostringstream s;
  s << function << ": argument '" << argument << "' has size " << got << ", expected " << expected;
  throw std::invalid_argument(s.str());
}

Model::Model() {
  Joint universe;
  universe.name = "universe";
  universe.type = JointType::Universe;
  joints.push_back(universe);
  inertias.push_back(Inertia::Zero());
  joint_index_["universe"] = 0;
  Frame f;
  f.name = "universe";
  f.type = FrameType::Operational;
  addFrame(f);
}

int Model::addJoint(int parent, JointType type, const SE3& placement, const std::string& jname,
                    const Eigen::Vector3d& axis) {
  if (parent < 0 || parent >= njoints())
    throw std::invalid_argument("Model::addJoint: joint '" + jname + "' has no valid parent");
  if (joint_index_.count(jname))
    throw std::invalid_argument("Model::addJoint: a joint named '" + jname + "' exists");
  {
    // Depth-first order (ARCHITECTURE.md §3): every subtree's dofs must stay contiguous.
    bool on_path = parent == 0;
    for (int a = njoints() - 1; a > 0 && !on_path; a = joints[a].parent) on_path = a == parent;
    if (!on_path)
      throw std::invalid_argument("Model::addJoint: joint '" + jname +
                                  "' breaks depth-first order (its parent must be the last joint "
                                  "added or one of its ancestors)");
  }
  if (type == JointType::Universe)
    throw std::invalid_argument("Model::addJoint: '" + jname + "' cannot be a universe joint");
  if (type == JointType::FreeFlyer && parent != 0)
    throw std::invalid_argument("Model::addJoint: free-flyer '" + jname +
                                "' must be attached to the universe");
  Joint j;
  j.name = jname;
  j.type = type;
  j.parent = parent;
  j.placement = placement;
  j.idx_q = nq;
  j.idx_v = nv;
  if (type == JointType::FreeFlyer) {
    j.nq = 7;
    j.nv = 6;
  } else {
    const double n = axis.norm();
    if (!(n > 1e-9) || !std::isfinite(n))
      throw std::invalid_argument("Model::addJoint: joint '" + jname + "' has a zero axis");
    j.axis = axis / n;
    for (int k = 0; k < 3; ++k)
      if (j.axis[k] == 1.0) j.alignedAxis = k;
    j.nq = 1;
    j.nv = 1;
  }
  // Dof-level parents (see parentDof in the header).
  int above = -1;
  for (int p = parent; p > 0; p = joints[p].parent)
    if (joints[p].nv > 0) {
      above = joints[p].idx_v + joints[p].nv - 1;
      break;
    }
  for (int k = 0; k < j.nv; ++k) parentDof.push_back(k == 0 ? above : j.idx_v + k - 1);
  for (int k = 0; k < j.nv; ++k) {
    nvSubtree.push_back(0);
    for (int r = j.idx_v + k; r >= 0; r = parentDof[r]) ++nvSubtree[r];
  }

  const int id = njoints();
  joints.push_back(j);
  inertias.push_back(Inertia::Zero());
  joint_index_[jname] = id;
  nq += j.nq;
  nv += j.nv;

  if (type == JointType::FreeFlyer) {
    appendRows(lowerPositionLimit, 7, -kInf);
    appendRows(upperPositionLimit, 7, kInf);
    lowerPositionLimit.tail(4).setConstant(-1.0);  // quaternion components
    upperPositionLimit.tail(4).setConstant(1.0);
    appendRows(velocityLimit, 6, kInf);
    appendRows(effortLimit, 6, kInf);
  } else {
    appendRows(lowerPositionLimit, 1, -kInf);
    appendRows(upperPositionLimit, 1, kInf);
    appendRows(velocityLimit, 1, kInf);
    appendRows(effortLimit, 1, kInf);
  }

  Frame f;
  f.name = jname;
  f.type = FrameType::Joint;
  f.parentJoint = id;
  // The frame this joint hangs from: the parent joint's own frame.
  f.parentFrame = frame_index_.count(joints[parent].name) ? frame_index_[joints[parent].name] : 0;
  addFrame(f);
  return id;
}

void Model::setJointLimits(int joint, double lower, double upper, double velocity, double effort) {
  if (joint <= 0 || joint >= njoints() || joints[joint].nq != 1)
    throw std::invalid_argument("Model::setJointLimits: joint index is not a 1-dof joint");
  const Joint& j = joints[joint];
  lowerPositionLimit[j.idx_q] = lower;
  upperPositionLimit[j.idx_q] = upper;
  velocityLimit[j.idx_v] = velocity;
  effortLimit[j.idx_v] = effort;
}

void Model::appendBodyToJoint(int joint, const Inertia& Y, const SE3& placement) {
  if (joint < 0 || joint >= njoints())
    throw std::invalid_argument("Model::appendBodyToJoint: no such joint");
  inertias[joint] += Y.transformedBy(placement);
}

int Model::addFrame(const Frame& frame) {
  for (const Frame& f : frames)
    if (f.name == frame.name && f.type == frame.type)
      throw std::invalid_argument("Model::addFrame: a " + std::string(toString(frame.type)) +
                                  " frame named '" + frame.name + "' exists");
  if (frame.parentJoint < 0 || frame.parentJoint >= njoints())
    throw std::invalid_argument("Model::addFrame: frame '" + frame.name + "' has no valid joint");
  const int id = nframes();
  frames.push_back(frame);
  frame_index_.emplace(frame.name, id);  // keeps the first frame of a name
  return id;
}

int Model::getFrameId(const std::string& n, FrameType type) const {
  for (int f = 0; f < nframes(); ++f)
    if (frames[f].name == n && frames[f].type == type) return f;
  throw std::out_of_range("model '" + name + "' has no " + toString(type) + " frame named '" + n +
                          "'");
}

bool Model::existJoint(const std::string& n) const {
  return joint_index_.count(n) > 0;
}
bool Model::existFrame(const std::string& n) const {
  return frame_index_.count(n) > 0;
}

int Model::getJointId(const std::string& n) const {
  auto it = joint_index_.find(n);
  if (it == joint_index_.end())
    throw std::out_of_range("model '" + name + "' has no joint named '" + n + "'");
  return it->second;
}

int Model::getFrameId(const std::string& n) const {
  auto it = frame_index_.find(n);
  if (it == frame_index_.end())
    throw std::out_of_range("model '" + name + "' has no frame named '" + n + "'");
  return it->second;
}

double Model::totalMass() const {
  double m = 0;
  for (int i = 1; i < njoints(); ++i) m += inertias[i].m;
  return m;
}

void Model::checkConfiguration(const Eigen::Ref<const Eigen::VectorXd>& q, const char* what) const {
  if (q.size() != nq) throwSizeError(what, "q", nq, q.size());
}

void Model::checkVelocity(const Eigen::Ref<const Eigen::VectorXd>& v, const char* what) const {
  if (v.size() != nv) throwSizeError(what, "v", nv, v.size());
}

}  // namespace stride
