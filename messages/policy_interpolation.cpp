#include "messages/policy_interpolation.hpp"

#include <cmath>
#include <stdexcept>

#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/spatial.hpp"

namespace stride::msg {

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

}  // namespace stride::msg
