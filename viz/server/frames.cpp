#include "viz/server/frames.hpp"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <type_traits>
#include <utility>

#include "config/model_hash.hpp"
#include "messages/validate.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/model.hpp"

namespace stride::viz {

namespace {

// Micrometres, microradians, micronewtons and microseconds are far below what the page can show;
// rounding there keeps the frames short (the JSON writer prints the shortest exact decimal).
double r6(double x) {
  return std::abs(x) < 1e9 ? std::round(x * 1e6) / 1e6 : x;
}

Json vec3(const Eigen::Vector3d& p) {
  return Json::array({r6(p.x()), r6(p.y()), r6(p.z())});
}

Json numbers(const double* x, int n) {
  Json a = Json::array();
  for (int i = 0; i < n; ++i) a.push_back(r6(x[i]));
  return a;
}

// A configuration from the wire with its base quaternion renormalized: the checks accept 1e-4
// off unit, forward kinematics wants a rotation.
void configuration(const Model& model, const std::vector<double>& in, Eigen::VectorXd& q) {
  q = Eigen::Map<const Eigen::VectorXd>(in.data(), model.nq);
  if (model.hasFreeFlyer()) q.segment<4>(3).normalize();
}

// A touch-down knot's `force` holds an impulse [N s], never shown as a force.
bool isImpulseKnot(const horizon_t& horizon, int k) {
  return k < static_cast<int>(horizon.impulse.size()) && horizon.impulse[k] != 0;
}

// Every contact of the robot, forces in world axes (LOCAL_WORLD_ALIGNED), without Baumgarte terms:
// a measured state is not integrated, so the rigid constraint itself (no contact acceleration) is
// the estimate.
ContactSet worldAlignedContacts(const Robot& robot) {
  ContactSet contacts;
  for (const ContactSpec& c : robot.contacts)
    contacts.add(robot.model, c.frame, c.dim, ReferenceFrame::LocalWorldAligned);
  return contacts;
}

}  // namespace

std::string hashText(std::int64_t hash) {
  char text[17];
  msg::formatHash(hash, text);
  return text;
}

FrameBuilder::FrameBuilder(const Robot& robot)
    : robot_(robot),
      nu_(actuatedDimension(robot.model)),
      data_(robot.model),
      contacts_(worldAlignedContacts(robot)),
      contact_data_(robot.model, contacts_),
      evaluator_(robot.model, nu_) {
  q_ = robot.default_q;
  v_.setZero(robot.model.nv);
  u_.setZero(nu_);
  tau_.setZero(robot.model.nv);
  // The robot applies at most its effort limits (stride-sim clamps, as motors saturate); a joint
  // without a limit (negative or infinite in the model) is not clamped.
  const int first = robot.model.nv - nu_;
  effort_.setConstant(nu_, std::numeric_limits<double>::infinity());
  for (int i = 0; i < nu_; ++i) {
    const double limit = robot.model.effortLimit[first + i];
    if (limit >= 0.0) effort_[i] = limit;
  }
  feet_.resize(robot.contacts.size(), Eigen::Vector3d::Zero());
}

FrameBuilder::~FrameBuilder() = default;

Json FrameBuilder::model(const robot_model_t* wire) const {
  Json frame = {{"type", "model"}, {"urdf", "/robot.urdf"}};
  Json joints = Json::array(), contacts = Json::array();
  if (wire != nullptr) {
    for (int j = 0; j < wire->njoints; ++j)
      joints.push_back({{"name", wire->joint_names[j]},
                        {"type", wire->joint_types[j]},
                        {"idx_q", wire->joint_idx_q[j]},
                        {"idx_v", wire->joint_idx_v[j]}});
    for (const std::string& c : wire->contact_frames) contacts.push_back(c);
    frame.update({{"robot", wire->robot},
                  {"model_hash", hashText(wire->model_hash)},
                  {"nq", wire->nq},
                  {"nv", wire->nv},
                  {"nu", wire->nu},
                  {"floating", wire->njoints > 0 && wire->joint_types[0] == "free-flyer"}});
  } else {
    for (const WireJoint& j : wireJoints(robot_.model))
      joints.push_back(
          {{"name", j.name}, {"type", j.type}, {"idx_q", j.idx_q}, {"idx_v", j.idx_v}});
    for (const ContactSpec& c : robot_.contacts) contacts.push_back(c.frame);
    frame.update({{"robot", robot_.name},
                  {"model_hash", hashText(modelHash(robot_))},
                  {"nq", robot_.model.nq},
                  {"nv", robot_.model.nv},
                  {"nu", nu_},
                  {"floating", robot_.model.hasFreeFlyer()}});
  }
  frame["joints"] = std::move(joints);
  frame["contacts"] = std::move(contacts);
  return frame;
}

std::uint64_t FrameBuilder::setPolicy(const policy_t& p) {
  const Model& model = robot_.model;
  // Overwrites the oldest held policy.
  HeldPolicy& held = policies_[serial_ % kPolicies];
  msg::Policy& policy = held.policy;
  if (policy.knots != p.knots) policy.resize(p.knots, model.nq, model.nv, nu_);
  // Times relative to knot 0: wall-clock stamps (~1.7e15 us) would cost the interpolation its
  // sub-microsecond resolution in double seconds.
  policy.t0 = 0.0;
  policy.dt = p.dt;
  for (int k = 0; k < p.knots; ++k) {
    std::copy(p.x_ref[k].begin(), p.x_ref[k].end(), policy.xRef(k));
    std::copy(p.u_ff[k].begin(), p.u_ff[k].end(), policy.uFf(k));
    std::copy(p.K[k].begin(), p.K[k].end(), policy.gain(k));
  }
  held.knot0_utime = p.knot0_utime;
  held.serial = ++serial_;
  return serial_;
}

bool FrameBuilder::estimateForces(const robot_state_t& state, std::uint64_t policy_serial,
                                  Json& forces) {
  const Model& model = robot_.model;
  const int nc = contacts_.size();
  if (serial_ == 0) {
    ++force_counts_.no_policy;
    return false;
  }
  if (state.ncontacts != nc) {
    ++force_counts_.no_contact_flags;
    return false;
  }
  const HeldPolicy* held = &policies_[(serial_ - 1) % kPolicies];  // the newest
  if (policy_serial != 0) {
    const HeldPolicy& asked = policies_[(policy_serial - 1) % kPolicies];
    if (asked.serial == policy_serial) held = &asked;
  }
  // In double: a policy's knot 0 may sit at any stamp, and the int64 difference overflowed for
  // one near -2^63 (undefined behaviour; the same value for every real pair of stamps).
  const double t =
      (static_cast<double>(state.utime) - static_cast<double>(held->knot0_utime)) * 1e-6;
  if (evaluator_.evaluate(held->policy, t, q_, v_, u_) == msg::PolicyStatus::Invalid) {
    ++force_counts_.failed;
    return false;
  }
  u_ = u_.cwiseMax(-effort_).cwiseMin(effort_);
  // τ = [0_6; u] for a floating base, u for a fixed one (actuatedDimension,
  // solver/multibody/model.hpp).
  tau_.setZero();
  tau_.tail(nu_) = u_;
  for (int c = 0; c < nc; ++c) contacts_.setActive(c, state.contact[c] != 0);
  // The ground only pushes: a closed contact whose force pulls (the torque lifts that foot) is
  // opened, the most pulling one first, and the rest solved again; at most once per contact.
  for (int pass = 0; pass <= nc; ++pass) {
    if (contactDynamics(model, data_, contacts_, contact_data_, q_, v_, tau_) !=
        ContactStatus::Ok) {
      ++force_counts_.failed;
      return false;
    }
    int pulling = -1, row = 0;
    double least = 0.0;
    for (int c = 0; c < nc; ++c) {
      if (!contacts_.isActive(c)) continue;
      const double fz = contact_data_.lambda[row + 2];  // world z: the ground's normal
      if (fz < least) {
        least = fz;
        pulling = c;
      }
      row += contacts_[c].dim;
    }
    if (pulling < 0) break;
    contacts_.setActive(pulling, false);
  }
  int row = 0;  // λ stacks the active contacts in order, each `dim` rows, force part first
  for (int c = 0; c < nc; ++c) {
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    if (contacts_.isActive(c)) {
      f = contact_data_.lambda.segment<3>(row);
      row += contacts_[c].dim;
    }
    forces.push_back(vec3(f));
  }
  ++force_counts_.estimated;
  return true;
}

Json FrameBuilder::state(const robot_state_t& state, std::uint64_t policy_serial) {
  const Model& model = robot_.model;
  configuration(model, state.q, q_);
  v_ = Eigen::Map<const Eigen::VectorXd>(state.v.data(), model.nv);
  Json contact = Json::array(), forces = Json::array();
  for (std::int8_t c : state.contact) contact.push_back(static_cast<int>(c));
  if (!estimateForces(state, policy_serial, forces)) forces = Json::array();
  return {{"type", "state"},
          {"t", r6(static_cast<double>(state.utime) * 1e-6)},
          {"q", numbers(q_.data(), model.nq)},
          {"contact", std::move(contact)},
          {"forces", std::move(forces)}};
}

void FrameBuilder::feetAt(const Eigen::VectorXd& q) {
  forwardKinematics(robot_.model, data_, q);
  for (std::size_t c = 0; c < feet_.size(); ++c)
    feet_[c] = updateFramePlacement(robot_.model, data_, contacts_[static_cast<int>(c)].frame).p;
}

Json FrameBuilder::planFrom(double t, const std::vector<const std::vector<double>*>& qs,
                            const std::vector<std::int32_t>& masks, Json forces) {
  const Model& model = robot_.model;
  const int nc = static_cast<int>(feet_.size());
  Json base = Json::array(), feet = Json::array(), footholds = Json::array();
  for (std::size_t k = 0; k < qs.size(); ++k) {
    configuration(model, *qs[k], q_);
    feetAt(q_);
    base.push_back(model.hasFreeFlyer() ? vec3(q_.head<3>()) : vec3(Eigen::Vector3d::Zero()));
    Json knot = Json::array();
    for (int c = 0; c < nc; ++c) knot.push_back(vec3(feet_[c]));
    feet.push_back(std::move(knot));
    // A stance starts at knot k when contact c is closed there and was not at k - 1 (or k = 0).
    // Knots without a known mask start nothing.
    if (k >= masks.size()) continue;
    for (int c = 0; c < nc; ++c) {
      const bool closed = (masks[k] >> c) & 1;
      const bool before = k > 0 && ((masks[k - 1] >> c) & 1);
      if (closed && !before)
        footholds.push_back(
            {r6(feet_[c].x()), r6(feet_[c].y()), r6(feet_[c].z()), static_cast<int>(c)});
    }
  }
  return {{"type", "plan"},
          {"t", r6(t)},
          {"base", std::move(base)},
          {"feet", std::move(feet)},
          {"footholds", std::move(footholds)},
          {"forces", std::move(forces)}};
}

Json FrameBuilder::plan(const horizon_t& h) {
  std::vector<const std::vector<double>*> qs;
  for (const std::vector<double>& q : h.q) qs.push_back(&q);
  // The planned forces now: knot 0's, or the first knot after it that is not a touch-down's
  // impulse.
  Json forces = Json::array();
  for (int k = 0; k < h.knots; ++k) {
    if (isImpulseKnot(h, k)) continue;
    for (int c = 0; c < h.ncontacts; ++c)
      forces.push_back(vec3(Eigen::Map<const Eigen::Vector3d>(h.force[k].data() + 3 * c)));
    break;
  }
  Json frame = planFrom(static_cast<double>(h.utime) * 1e-6, qs, h.contact_mask, std::move(forces));
  // The footholds the gait generator chose (issue 31), as the controller sent them.
  Json chosen = Json::array();
  for (int i = 0; i < h.nfootholds; ++i) {
    const std::vector<double>& p = h.foothold[i];
    chosen.push_back({r6(p[0]), r6(p[1]), r6(p[2]), static_cast<int>(h.foothold_contact[i]),
                      r6(h.foothold_time[i]), static_cast<int>(h.foothold_source[i])});
  }
  frame["chosen_footholds"] = std::move(chosen);
  return frame;
}

Json FrameBuilder::plan(const policy_t& p) {
  std::vector<const std::vector<double>*> qs;
  for (const std::vector<double>& x : p.x_ref) qs.push_back(&x);  // q is x's head
  Json frame = planFrom(static_cast<double>(p.knot0_utime) * 1e-6, qs, {p.phase}, Json::array());
  frame["chosen_footholds"] = Json::array();  // a policy does not carry them
  return frame;
}

Json FrameBuilder::status(const mpc_status_t& s, const command_t* requested) {
  Json frame = {{"type", "status"},
                {"t", r6(static_cast<double>(s.utime) * 1e-6)},
                {"tick", s.tick},
                {"tick_ms", r6(s.tick_ms)},
                {"solve_ms", r6(s.solve_ms)},
                {"cost", s.cost},
                {"iterations", s.iterations},
                {"solver_status", s.solver_status},
                {"policy_status", static_cast<int>(s.policy_status)},
                {"deadline_misses", s.deadline_misses},
                {"rejected", s.rejected_messages},
                {"wrong_model", s.wrong_model},
                {"gait", s.gait},
                {"command", numbers(s.command, 4)}};
  if (requested != nullptr)
    frame["requested"] = {{"vx", r6(requested->vx)},
                          {"vy", r6(requested->vy)},
                          {"yaw_rate", r6(requested->yaw_rate)},
                          {"gait", requested->gait},
                          {"body_height", r6(requested->body_height)}};
  return frame;
}

Json FrameBuilder::terrain(const terrain_t& map) {
  // Millimetres: a map's cells are centimetres wide and its heights no finer than its sensor, and
  // short numbers keep a 100 x 100 map's frame near 50 kB (it goes to every browser twice a
  // second). n / 1000, not n * 0.001: the double nearest n / 1000 prints as the short decimal.
  const double per_metre = std::round(1.0 / kTerrainHeightStep);
  Json heights = Json::array();
  heights.get_ref<Json::array_t&>().reserve(static_cast<std::size_t>(map.rows) * map.cols);
  for (const std::vector<float>& row : map.height)
    for (const float h : row) {
      if (std::isnan(h))
        heights.push_back(nullptr);
      else
        heights.push_back(std::round(static_cast<double>(h) * per_metre) / per_metre);
    }
  return {{"type", "terrain"},
          {"t", r6(static_cast<double>(map.utime) * 1e-6)},
          {"origin_x", r6(map.origin_x)},
          {"origin_y", r6(map.origin_y)},
          {"resolution", r6(map.resolution)},
          {"rows", map.rows},
          {"cols", map.cols},
          {"heights", std::move(heights)}};
}

}  // namespace stride::viz
