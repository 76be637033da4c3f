#include "locomotion/locomotion_problem.hpp"

#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "solver/contact/contact_dynamics.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/ocp/residual_com.hpp"
#include "solver/ocp/residual_contact.hpp"
#include "solver/ocp/residual_cop.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"

namespace stride {

namespace {
Eigen::VectorXd stateWeights(const Model& model, const LocomotionWeights& w) {
  const int nv = model.nv;
  if (w.state.size() > 0) {
    if (w.state.size() != 2 * nv)
      throw std::invalid_argument("LocomotionProblem: weights.state has size " +
                                  std::to_string(w.state.size()) +
                                  ", expected 2 nv = " + std::to_string(2 * nv));
    return w.state;
  }
  Eigen::VectorXd s(2 * nv);
  s.head(nv).setConstant(w.joint_position);
  s.tail(nv).setConstant(w.joint_velocity);
  if (model.hasFreeFlyer()) {
    s.head<3>().setConstant(w.base_position);
    s.segment<3>(3).setConstant(w.base_orientation);
    s.segment<3>(nv).setConstant(w.base_velocity);
    s.segment<3>(nv + 3).setConstant(w.base_velocity);
  }
  return s;
}

void checkOptions(const Model& model, const Eigen::VectorXd& x_nominal,
                  const LocomotionOptions& o) {
  if (x_nominal.size() != model.nq + model.nv || !x_nominal.allFinite())
    throw std::invalid_argument("LocomotionProblem: x_nominal must be finite of size nq + nv = " +
                                std::to_string(model.nq + model.nv));
  if (!(o.dt > 0.0) || !std::isfinite(o.dt))
    throw std::invalid_argument("LocomotionProblem: dt must be positive and finite");
  if (o.knots < 1) throw std::invalid_argument("LocomotionProblem: knots must be at least 1");
  if (!(o.mu > 0.0)) throw std::invalid_argument("LocomotionProblem: mu must be positive");
}

// The torques that hold posture q still on each contact mask: g(q) = Sᵀ u + Jcᵀ λ at rest; the
// base rows fix λ (minimum norm among the forces that carry the weight), the joint rows then give
// u. With no contact closed (flight) the body falls as one in the uniform gravity field, and the
// torque that holds a posture is zero: a free-floating base's g(q) = -M a_g for the base's
// spatial acceleration a_g = -g, so M v̇ + g(q) = Sᵀ u holds with v̇ = a_g and u = 0. (The
// fixed-base gravity torques g(q)'s joint rows would fling the legs in flight: issue 45.)
std::vector<Eigen::VectorXd> holdingTorques(const Model& model, const ContactSet& contacts,
                                            const Eigen::VectorXd& q) {
  const int nv = model.nv, nu = actuatedDimension(model), nc = contacts.size();
  Data data(model);
  const Eigen::VectorXd g = computeGeneralizedGravity(model, data, q);
  ContactSet set = contacts;
  ContactData cd(model, set);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(nv);
  const int na = nv - nu;  // unactuated (base) dofs
  std::vector<Eigen::VectorXd> u_hold;
  for (unsigned mask = 0; mask < (1u << nc); ++mask) {
    for (int c = 0; c < nc; ++c) set.setActive(c, (mask >> c) & 1u);
    Eigen::VectorXd u = g.tail(nu);
    if (na > 0 && set.nc() == 0) u.setZero();
    if (na > 0 && set.nc() > 0 &&
        contactDynamics(model, data, set, cd, q, zero, zero) == ContactStatus::Ok) {
      const Eigen::MatrixXd Jc = cd.Jc.topRows(set.nc());
      const Eigen::VectorXd lambda =
          Jc.leftCols(na).transpose().completeOrthogonalDecomposition().solve(g.head(na));
      u -= Jc.rightCols(nu).transpose() * lambda;
    }
    u_hold.push_back(u);
  }
  return u_hold;
}

// knots and dt from the grid, when there is one.
LocomotionOptions withGrid(LocomotionOptions o) {
  if (o.grid.empty()) return o;
  o.knots = 0;
  for (std::size_t i = 0; i < o.grid.size(); ++i) {
    const KnotSegment& s = o.grid[i];
    if (s.knots < 1 || !(s.dt > 0.0) || !std::isfinite(s.dt))
      throw std::invalid_argument(
          "LocomotionProblem: every grid segment needs at least one knot and a positive duration");
    if (i > 0 && s.dt < o.grid[i - 1].dt)
      throw std::invalid_argument("LocomotionProblem: the grid's durations must not decrease");
    o.knots += s.knots;
  }
  o.dt = o.grid.front().dt;
  return o;
}
}  // namespace

LocomotionProblem::LocomotionProblem(const Model& model, const ContactSet& contacts,
                                     const Eigen::VectorXd& x_nominal,
                                     const LocomotionOptions& options)
    : model_(model), contacts_(contacts), x_nominal_(x_nominal), options_(withGrid(options)) {
  checkOptions(model, x_nominal, options_);
  const int nq = model.nq, nu = actuatedDimension(model);
  const int nc = contacts_.size();
  if (nc > kMaxContacts)
    throw std::invalid_argument("LocomotionProblem: at most " + std::to_string(kMaxContacts) +
                                " contacts");
  const LocomotionWeights& w = options.weights;
  const Eigen::VectorXd w_state = stateWeights(model, w);
  const auto q = x_nominal.head(nq);

  Data data(model);
  framesForwardKinematics(model, data, q);
  const Eigen::Vector3d com_nominal = centerOfMass(model, data, q);

  u_hold_ = holdingTorques(model, contacts_, q);
  u_ref_ = u_hold_[0];

  cone_term_.resize(nc);
  swing_term_.resize(nc);
  cop_term_.assign(nc, -1);
  swing_rot_term_.assign(nc, -1);
  const bool with_cop = options.sole_half_extents.minCoeff() > 0.0;
  const double swing_xy = w.swing_horizontal >= 0.0 ? w.swing_horizontal : w.swing;
  swing_ = w.swing;
  swing_xy_ = swing_xy;
  std::vector<std::unique_ptr<ActionModel>> running;
  // One multibody workspace per thread the problem may use (solver/ocp/knot.hpp, SharedWorkspace).
  auto workspace = std::make_shared<SharedWorkspace>(model, std::max(omp_get_max_threads(), 2));
  for (int k = 0; k < options_.knots; ++k) {
    auto knot = std::make_unique<KnotModel>(model, contacts_, options_.dt, workspace);
    knot->setIntegrator(options_.integrator);
    CostModel& costs = knot->costs();
    state_term_ = costs.add("state", std::make_unique<StateResidual>(model, nu, x_nominal),
                            Activation::weightedQuadratic(w_state));
    control_term_ = costs.add("control", std::make_unique<ControlResidual>(model, nu),
                              Activation::quadratic(nu), w.control);
    if (w.com > 0.0)
      com_term_ = costs.add("com", std::make_unique<ComPositionResidual>(model, nu, com_nominal),
                            Activation::quadratic(3), w.com);
    for (int c = 0; c < nc; ++c) {
      const std::string& name = contacts_[c].name;
      cone_term_[c] = costs.add("cone_" + name,
                                std::make_unique<FrictionConeResidual>(
                                    model, nu, contacts_, name, options.mu,
                                    Eigen::Matrix3d::Identity(), options.min_normal_force),
                                FrictionConeResidual::activation(), w.friction);
      if (with_cop && contacts_[c].dim == 6)
        cop_term_[c] = costs.add("cop_" + name,
                                 std::make_unique<CenterOfPressureResidual>(
                                     model, nu, contacts_, name, options.sole_half_extents),
                                 CenterOfPressureResidual::activation(), w.cop);
      swing_term_[c] =
          costs.add("swing_" + name,
                    std::make_unique<FrameTranslationResidual>(model, nu, name,
                                                               data.oMf[contacts_[c].frame].p),
                    Activation::weightedQuadratic(Eigen::Vector3d(swing_xy, swing_xy, w.swing)));
      if (w.swing_rotation > 0.0 && contacts_[c].dim == 6)
        swing_rot_term_[c] = costs.add("swing_rot_" + name,
                                       std::make_unique<FrameRotationResidual>(
                                           model, nu, name, data.oMf[contacts_[c].frame].R),
                                       Activation::quadratic(3), w.swing_rotation);
    }
    running.push_back(std::move(knot));
  }
  auto terminal = std::make_unique<TerminalModel>(model);
  terminal->costs().add("state", std::make_unique<StateResidual>(model, 0, x_nominal),
                        Activation::weightedQuadratic(w.terminal_state * w_state));
  problem_ = std::make_unique<ShootingProblem>(x_nominal, std::move(running), std::move(terminal));

  const double inf = std::numeric_limits<double>::infinity();
  u_lower_ = Eigen::VectorXd::Constant(nu, -inf);
  u_upper_ = Eigen::VectorXd::Constant(nu, inf);
  if (options.torque_limits) {
    u_upper_ = options.torque_limit_fraction * model.effortLimit.tail(nu);
    u_lower_ = -u_upper_;
  }
  x_ref_ = x_nominal_;
  knot_time_.assign(options_.knots + 1, 0.0);
  segments_ = options_.grid;
  if (segments_.empty()) segments_.push_back({options_.knots, options_.dt});
  for (const KnotSegment& s : segments_) span_ += s.knots * s.dt;
  const CostModel& costs = static_cast<const KnotModel&>(problem_->knot(0)).costs();
  for (int i = 0; i < costs.size(); ++i) base_weight_.push_back(costs[i].weight);
}

bool LocomotionProblem::update(double t0, const GaitGenerator& reference) {
  // A clock that is not finite (or absurdly far) would index the plan out of range: refuse it.
  if (!std::isfinite(t0) || std::abs(t0) > 1e9) return false;
  t0_ = t0;
  const int T = problem_->horizon(), nc = contacts_.size();
  const double dt0 = options_.dt;
  // An impulse knot takes no time: it is inserted at its touch-down time and the contact knot
  // after it starts at that same time.
  double t = t0;
  double t_before = t0 - dt0;  // the last contact knot's start: a contact that was open there lands
  int seg = 0, left = segments_[0].knots;  // the grid segment and its knots still due
  bool after_impulse = false;
  for (int k = 0; k < T; ++k) {
    knot_time_[k] = t;
    // Every running knot was built as a KnotModel (shift only reorders them).
    auto& knot = static_cast<KnotModel&>(problem_->knot(k));
    CostModel& costs = knot.costs();
    const unsigned mask = reference.mask(t), before = reference.mask(t_before);
    bool touchdown = false;
    for (int c = 0; c < nc; ++c) {
      const bool closed = (mask >> c) & 1u;
      const bool lands = closed && !((before >> c) & 1u);
      touchdown = touchdown || lands;
      knot.contacts().setActive(c, closed);
      costs[cone_term_[c]].active = closed;
      // The cone along the surface normal where the foot stands (forces are world-aligned).
      if (closed)
        static_cast<FrictionConeResidual&>(*costs[cone_term_[c]].residual)
            .setSurfaceRotation(reference.surfaceRotation(c, t));
      if (cop_term_[c] >= 0) {
        costs[cop_term_[c]].active = closed;
        // The sole's heading where it stands (or will land), for its centre of pressure.
        if (closed)
          static_cast<CenterOfPressureResidual&>(*costs[cop_term_[c]].residual)
              .setSurface(reference.footRotation(c, t));
      }
      CostTerm& swing = costs[swing_term_[c]];
      swing.active = !closed || lands;
      if (swing.active) {
        static_cast<FrameTranslationResidual&>(*swing.residual).setReference(reference.foot(c, t));
        swing.activation.weights.head<2>().setConstant(
            reference.footholdNearEdge(c, t) ? swing_ : swing_xy_);
      }
      if (swing_rot_term_[c] >= 0) {
        CostTerm& turn = costs[swing_rot_term_[c]];
        turn.active = swing.active;
        if (turn.active)
          static_cast<FrameRotationResidual&>(*turn.residual)
              .setReference(reference.footRotation(c, t));
      }
    }
    const bool impulse = touchdown && options_.impulses && !after_impulse;
    knot.setMode(impulse ? KnotMode::Impulse : KnotMode::Contact);
    // A contact knot's costs weigh its duration (an impulse knot's, one knot of dt0).
    const double dt = impulse ? dt0 : contactKnotDuration(t, seg, left);
    const double scale = dt / dt0;
    knot.setDt(dt);
    for (int i = 0; i < costs.size(); ++i) costs[i].weight = scale * base_weight_[i];
    // An impulse knot's cones bound impulses Λ ≈ f dt0 [N s], weighted as the same mean force. No
    // minimum there: a soft landing (no impact speed) has zero impulses, and rightly so.
    const double f_min = impulse ? 0.0 : options_.min_normal_force;
    const double w_cone = scale * options_.weights.friction / (impulse ? dt0 * dt0 : 1.0);
    for (int c = 0; c < nc; ++c) {
      CostTerm& cone = costs[cone_term_[c]];
      cone.weight = w_cone;
      static_cast<FrictionConeResidual&>(*cone.residual).setMinimumNormalForce(f_min);
      if (cop_term_[c] >= 0)
        costs[cop_term_[c]].weight = scale * options_.weights.cop / (impulse ? dt0 * dt0 : 1.0);
    }
    reference.state(t, x_ref_);
    static_cast<StateResidual&>(*costs[state_term_].residual).setReference(x_ref_);
    static_cast<ControlResidual&>(*costs[control_term_].residual)
        .setReference(holdingControlAt(mask, reference.height(t)));
    if (com_term_ >= 0)
      static_cast<ComPositionResidual&>(*costs[com_term_].residual).setReference(reference.com(t));
    after_impulse = impulse;
    if (!impulse) {
      t_before = t;
      t += dt;
    }
  }
  knot_time_[T] = t;
  auto& terminal = static_cast<TerminalModel&>(problem_->terminal());
  reference.state(t, x_ref_);
  static_cast<StateResidual&>(*terminal.costs()[0].residual).setReference(x_ref_);
  return true;
}

void LocomotionProblem::setPostures(const std::vector<Eigen::VectorXd>& joints, double max_height) {
  u_posture_.clear();
  max_height_ = max_height;
  if (joints.size() < 2 || !(max_height > 0.0)) return;
  const int nq = model_.nq;
  Eigen::VectorXd q = x_nominal_.head(nq);
  for (const Eigen::VectorXd& j : joints) {
    if (j.size() != nq - 7)
      throw std::invalid_argument("LocomotionProblem::setPostures: a posture of the wrong size");
    q.tail(nq - 7) = j;
    u_posture_.push_back(holdingTorques(model_, contacts_, q));
  }
}

const Eigen::VectorXd& LocomotionProblem::holdingControlAt(unsigned mask, double height) {
  const int n = static_cast<int>(u_posture_.size());
  if (n < 2) return u_hold_[mask];
  // The joints' reference's blend (GaitGenerator::state), at the same commanded height.
  const PostureBlend b = postureBlend(height, max_height_, n);
  u_ref_ = (1.0 - b.weight) * u_posture_[b.lower][mask] + b.weight * u_posture_[b.lower + 1][mask];
  return u_ref_;
}

double LocomotionProblem::contactKnotDuration(double t, int& seg, int& left) const {
  const int n = static_cast<int>(segments_.size());
  for (;;) {
    if (left > 0 || seg + 1 == n) {  // the segment's own knots (the last one's, to the end)
      if (left > 0) --left;
      return segments_[seg].dt;
    }
    // The segment's knots are placed: it goes on until the next segment's boundaries on the plan
    // clock (multiples of its dt), so that the longer knots keep their times from tick to tick.
    const double next = segments_[seg + 1].dt;
    const double boundary = std::ceil((t - kPlanTimeEpsilon) / next) * next;
    if (boundary - t <= kPlanTimeEpsilon) {
      ++seg;
      left = segments_[seg].knots;
      continue;
    }
    return std::min(segments_[seg].dt, boundary - t);
  }
}

void LocomotionProblem::referenceWarmStart(const GaitGenerator& reference,
                                           std::vector<Eigen::VectorXd>& xs,
                                           std::vector<Eigen::VectorXd>& us) const {
  const int T = problem_->horizon();
  xs.resize(T + 1, x_nominal_);
  us.resize(T);
  for (int k = 0; k <= T; ++k) reference.state(knot_time_[k], xs[k]);
  for (int k = 0; k < T; ++k) {
    const auto& knot = static_cast<const KnotModel&>(problem_->knot(k));
    us[k] = static_cast<const ControlResidual&>(*knot.costs()[control_term_].residual).reference();
  }
}

std::vector<Eigen::VectorXd> LocomotionProblem::holdingControlsOf(const Eigen::VectorXd& q) const {
  return holdingTorques(model_, contacts_, q);
}

void LocomotionProblem::measuredWarmStart(const Eigen::VectorXd& x0,
                                          std::vector<Eigen::VectorXd>& xs,
                                          std::vector<Eigen::VectorXd>& us) const {
  const int T = problem_->horizon(), nq = model_.nq;
  const std::vector<Eigen::VectorXd> u_hold = holdingControlsOf(x0.head(nq));
  Eigen::VectorXd rest = x0;
  rest.tail(model_.nv).setZero();
  xs.assign(T + 1, rest);
  xs[0] = x0;
  us.resize(T);
  for (int k = 0; k < T; ++k) us[k] = u_hold[contactMask(k)];
}

unsigned LocomotionProblem::contactMask(int k) const {
  const ContactSet& set = static_cast<const KnotModel&>(problem_->knot(k)).contacts();
  unsigned mask = 0;
  for (int c = 0; c < set.size(); ++c)
    if (set.isActive(c)) mask |= 1u << c;
  return mask;
}

}  // namespace stride
