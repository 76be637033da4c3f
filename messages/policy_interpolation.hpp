#pragma once
// The policy a robot applies between controller updates, as the wire carries it (policy_t;
// ARCHITECTURE.md §1, §3):
//   τ(t, x) = u_ff(t) + K(t) (x_ref(t) ⊖ x),
// with knots k at t0 + k dt: u_ff and K interpolated linearly, x_ref on the manifold
// (q_k ⊕ s (q_{k+1} ⊖ q_k), v linearly). Before t0 knot 0 is used; past the last knot the last
// knot is held and the evaluation reports the policy as exhausted.
//
// Part of the wire contract, so it sits beside the messages (library stride_policy, messages/
// README.md, "Policy interpolation"): whoever receives a policy_t reads it the same way, the mock
// robot (stride-sim) applying it and the viewer (stride-viz) showing the torques it asks. It needs
// the multibody Lie group for ⊖ and ⊕, nothing of the solver above it, nor of the mock robot.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "solver/multibody/model.hpp"

namespace stride::msg {

// A policy as it travels on the wire (policy_t): flat row-major arrays.
struct Policy {
  double t0 = 0.0;  // time of knot 0 (s, the simulator's clock)
  double dt = 0.0;  // time between knots
  int knots = 0, nq = 0, nv = 0, nu = 0;
  std::vector<double> x_ref;  // knots × (nq + nv): [q; v] per knot
  std::vector<double> u_ff;   // knots × nu
  std::vector<double> K;      // knots × nu × 2nv: K[k](i, j) at k·nu·2nv + i·2nv + j

  // Sizes the arrays (zero-filled). Allocates: call when a policy of a new shape arrives.
  void resize(int knots, int nq, int nv, int nu);
  // Sizes agree with each other and with the model, dt > 0 (or a single knot), every number
  // finite, every knot's quaternion unit (1e-6). Not for the tick: call once per received policy.
  bool isValid(const Model& model, int nu) const;

  double* xRef(int k) { return x_ref.data() + static_cast<size_t>(k) * (nq + nv); }
  double* uFf(int k) { return u_ff.data() + static_cast<size_t>(k) * nu; }
  double* gain(int k) { return K.data() + static_cast<size_t>(k) * nu * 2 * nv; }
  const double* xRef(int k) const { return x_ref.data() + static_cast<size_t>(k) * (nq + nv); }
  const double* uFf(int k) const { return u_ff.data() + static_cast<size_t>(k) * nu; }
  const double* gain(int k) const { return K.data() + static_cast<size_t>(k) * nu * 2 * nv; }
};

enum class PolicyStatus : std::uint8_t {
  Ok,           // t within [t0, t0 + (knots − 1) dt]
  BeforeStart,  // t < t0: knot 0 used
  Exhausted,    // t past the last knot: the last knot held (the caller counts it)
  Invalid,      // shapes do not match the model: τ set to zero
};
const char* toString(PolicyStatus status);

// Evaluates a Policy for one model without allocating (workspaces sized at construction). Keeps a
// reference to the model: it must outlive the evaluator.
class PolicyEvaluator {
 public:
  PolicyEvaluator(const Model& model, int nu);

  // τ (size nu) at time t and state x = (q, v). Only cheap shape checks here: validate a received
  // policy once with Policy::isValid.
  PolicyStatus evaluate(const Policy& policy, double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& v,
                        Eigen::Ref<Eigen::VectorXd> tau);

  // The interpolated reference of the last evaluate(), and x_ref ⊖ x (size 2nv).
  const Eigen::VectorXd& qRef() const { return q_ref_; }
  const Eigen::VectorXd& vRef() const { return v_ref_; }
  const Eigen::VectorXd& stateError() const { return dx_; }

 private:
  const Model& model_;
  int nu_;
  Eigen::VectorXd q_ref_, v_ref_, dq_, dx_, u_, tmp_;
};

}  // namespace stride::msg
