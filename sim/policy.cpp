#include "sim/policy.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "solver/multibody/crba.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride::sim {

namespace {
using ConstMapVec = Eigen::Map<const Eigen::VectorXd>;
using ConstMapRowMat = Eigen::Map<const RowMatrixXd>;

bool allFinite(const std::vector<double>& x) {
  for (double d : x)
    if (!std::isfinite(d)) return false;
  return true;
}
}  // namespace

const char* toString(PolicyStatus status) {
  switch (status) {
    case PolicyStatus::Ok:
      return "ok";
    case PolicyStatus::BeforeStart:
      return "before start";
    case PolicyStatus::Exhausted:
      return "exhausted";
    case PolicyStatus::Invalid:
      return "invalid";
  }
  return "?";
}

void Policy::resize(int knots_, int nq_, int nv_, int nu_) {
  knots = knots_;
  nq = nq_;
  nv = nv_;
  nu = nu_;
  x_ref.assign(static_cast<size_t>(knots) * (nq + nv), 0.0);
  u_ff.assign(static_cast<size_t>(knots) * nu, 0.0);
  K.assign(static_cast<size_t>(knots) * nu * 2 * nv, 0.0);
}

bool Policy::isValid(const Model& model, int nu_expected) const {
  if (knots < 1 || nq != model.nq || nv != model.nv || nu != nu_expected) return false;
  if (!std::isfinite(t0) || !std::isfinite(dt) || (knots > 1 && !(dt > 0.0))) return false;
  if (x_ref.size() != static_cast<size_t>(knots) * (nq + nv) ||
      u_ff.size() != static_cast<size_t>(knots) * nu ||
      K.size() != static_cast<size_t>(knots) * nu * 2 * nv)
    return false;
  if (!allFinite(x_ref) || !allFinite(u_ff) || !allFinite(K)) return false;
  if (model.hasFreeFlyer()) {
    for (int k = 0; k < knots; ++k) {
      const double n = Eigen::Map<const Eigen::Vector4d>(xRef(k) + 3).norm();
      if (std::abs(n - 1.0) > 1e-6) return false;
    }
  }
  return true;
}

PolicyEvaluator::PolicyEvaluator(const Model& model, int nu) : model_(model), nu_(nu) {
  if (nu < 0 || nu > model.nv) throw std::invalid_argument("PolicyEvaluator: nu out of range");
  q_ref_ = neutral(model);
  v_ref_.setZero(model.nv);
  dq_.setZero(model.nv);
  dx_.setZero(2 * model.nv);
}

PolicyStatus PolicyEvaluator::evaluate(const Policy& policy, double t,
                                       const Eigen::Ref<const Eigen::VectorXd>& q,
                                       const Eigen::Ref<const Eigen::VectorXd>& v,
                                       Eigen::Ref<Eigen::VectorXd> tau) {
  const int nq = model_.nq, nv = model_.nv;
  if (tau.size() != nu_) throwSizeError("PolicyEvaluator::evaluate", "tau", nu_, tau.size());
  // Shape checks only (O(1)): the contents were validated once on reception (Policy::isValid).
  if (policy.knots < 1 || policy.nq != nq || policy.nv != nv || policy.nu != nu_ ||
      policy.x_ref.size() != static_cast<size_t>(policy.knots) * (nq + nv) ||
      policy.u_ff.size() != static_cast<size_t>(policy.knots) * nu_ ||
      policy.K.size() != static_cast<size_t>(policy.knots) * nu_ * 2 * nv ||
      (policy.knots > 1 && !(policy.dt > 0.0)) || q.size() != nq || v.size() != nv ||
      !std::isfinite(t)) {
    tau.setZero();
    return PolicyStatus::Invalid;
  }

  // Knot k and the fraction s of the way to k + 1.
  PolicyStatus status = PolicyStatus::Ok;
  int k = 0;
  double s = 0.0;
  const double u = policy.knots > 1 ? (t - policy.t0) / policy.dt : t - policy.t0;
  const int last = policy.knots - 1;
  if (u < 0.0) {
    status = PolicyStatus::BeforeStart;
  } else if (u >= last) {
    k = last;
    if (u > last) status = PolicyStatus::Exhausted;
  } else {
    k = static_cast<int>(std::floor(u));
    s = u - k;
  }

  // x_ref(t): q on the manifold, v linearly.
  const ConstMapVec qk(policy.xRef(k), nq), vk(policy.xRef(k) + nq, nv);
  if (s > 0.0) {
    const ConstMapVec qk1(policy.xRef(k + 1), nq), vk1(policy.xRef(k + 1) + nq, nv);
    difference(model_, qk, qk1, dq_);
    dq_ *= s;
    integrate(model_, qk, dq_, q_ref_);
    v_ref_ = (1.0 - s) * vk + s * vk1;
  } else {
    q_ref_ = qk;
    v_ref_ = vk;
  }

  // x_ref ⊖ x = difference(x → x_ref), in R^(2nv).
  difference(model_, q, q_ref_, dx_.head(nv));
  dx_.tail(nv) = v_ref_ - v;

  // K is linear in the interpolation, so blending the two knots' τ equals τ of the blended knot.
  const ConstMapRowMat Kk(policy.gain(k), nu_, 2 * nv);
  tau = (1.0 - s) * ConstMapVec(policy.uFf(k), nu_);
  tau.noalias() += (1.0 - s) * (Kk * dx_);
  if (s > 0.0) {
    const ConstMapRowMat Kk1(policy.gain(k + 1), nu_, 2 * nv);
    tau += s * ConstMapVec(policy.uFf(k + 1), nu_);
    tau.noalias() += s * (Kk1 * dx_);
  }
  return status;
}

HoldPolicy::HoldPolicy(const Model& model, const Eigen::VectorXd& q_ref_, double kp_, double kd_,
                       double step_dt)
    : q_ref(q_ref_) {
  model.checkConfiguration(q_ref, "q_ref");
  const int first = model.hasFreeFlyer() ? 6 : 0;
  const int nu = model.nv - first;
  kp = Eigen::VectorXd::Constant(nu, kp_);
  kd = Eigen::VectorXd::Constant(nu, kd_);
  if (step_dt > 0.0) {
    // The inertia a joint's PD drives when every other joint (and the base) moves freely:
    // 1 / (M⁻¹)_ii, smaller than M_ii wherever links couple (an elbow swinging with its shoulder).
    Data data(model);
    const Eigen::MatrixXd Minv =
        crba(model, data, q_ref).llt().solve(Eigen::MatrixXd::Identity(model.nv, model.nv));
    for (int i = 0; i < nu; ++i) {
      const double m = 1.0 / Minv(first + i, first + i);
      kd[i] = std::min(kd[i], 0.5 * m / step_dt);
      kp[i] = std::min(kp[i], 0.25 * m / (step_dt * step_dt));
    }
  }
}

void HoldPolicy::torque(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& v,
                        Eigen::Ref<Eigen::VectorXd> tau) const {
  const int first = model.hasFreeFlyer() ? 6 : 0;
  for (int j = 1; j < model.njoints(); ++j) {
    const Joint& jt = model.joints[j];
    if (jt.type == JointType::FreeFlyer) continue;
    // 1-dof joints: one configuration and one velocity entry.
    const int i = jt.idx_v - first;
    tau[i] = kp[i] * (q_ref[jt.idx_q] - q[jt.idx_q]) - kd[i] * v[jt.idx_v];
  }
}

StandDown::StandDown(const Model& model, const HoldPolicy& hold,
                     const std::vector<int>& contact_frames, const StandDownOptions& options)
    : model_(model),
      hold_(hold),
      options_(options),
      chains_(hold.kp.size(), 0u),
      planted_(hold.kp.size(), 0),
      q_start_(hold.q_ref),
      u_start_(Eigen::VectorXd::Zero(hold.kp.size())) {
  const int first = model.hasFreeFlyer() ? 6 : 0;
  for (std::size_t c = 0; c < contact_frames.size() && c < 32; ++c)
    for (int j = model.frames.at(contact_frames[c]).parentJoint; j > 0; j = model.joints[j].parent)
      if (model.joints[j].type != JointType::FreeFlyer)
        chains_[model.joints[j].idx_v - first] |= 1u << c;
}

void StandDown::begin(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& u_last, unsigned on_ground) {
  t0_ = t;
  q_start_ = q;
  u_start_ = u_last;
  for (std::size_t i = 0; i < chains_.size(); ++i) planted_[i] = (chains_[i] & on_ground) != 0;
}

void StandDown::torque(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& v,
                       Eigen::Ref<Eigen::VectorXd> tau) const {
  const double s = options_.ramp > 0.0 ? std::clamp((t - t0_) / options_.ramp, 0.0, 1.0) : 1.0;
  const int first = model_.hasFreeFlyer() ? 6 : 0;
  for (int j = 1; j < model_.njoints(); ++j) {
    const Joint& jt = model_.joints[j];
    if (jt.type == JointType::FreeFlyer) continue;
    const int i = jt.idx_v - first;  // 1-dof joints, as HoldPolicy
    const double start = q_start_[jt.idx_q];
    const double target = planted_[i] ? start : start + s * (hold_.q_ref[jt.idx_q] - start);
    tau[i] =
        (1.0 - s) * u_start_[i] + hold_.kp[i] * (target - q[jt.idx_q]) - hold_.kd[i] * v[jt.idx_v];
  }
}

}  // namespace stride::sim
