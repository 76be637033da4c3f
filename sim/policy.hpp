#pragma once
// The policy the robot applies between controller updates (ARCHITECTURE.md §1, §3):
//   τ(t, x) = u_ff(t) + K(t) (x_ref(t) ⊖ x),
// with knots k at t0 + k dt: u_ff and K interpolated linearly, x_ref on the manifold
// (q_k ⊕ s (q_{k+1} ⊖ q_k), v linearly). Before t0 knot 0 is used; past the last knot the last
// knot is held and the evaluation reports the policy as exhausted.
// Also the fallback for when no policy has arrived yet: a joint PD holding a posture.

#include <cstdint>
#include <vector>

#include "solver/multibody/model.hpp"

namespace stride::sim {

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

// The fallback policy: a joint PD holding q_ref, τ = Kp (q_ref − q) − Kd v on the actuated joints
// (the base is not actuated). Gains per actuated joint.
struct HoldPolicy {
  Eigen::VectorXd q_ref;   // nq: only its joint entries are used
  Eigen::VectorXd kp, kd;  // nu

  HoldPolicy() = default;
  // The same gains on every joint. With step_dt > 0 they are capped per joint for the simulator's
  // explicit step: kd_i ≤ m_i / (2 dt) and kp_i ≤ m_i / (4 dt²), m_i = 1 / (M⁻¹)_ii the inertia
  // the joint drives at q_ref when everything else moves freely. A PD evaluated once per step on a
  // light link (a humanoid's forearm coupled with its shoulder) oscillates step to step above
  // kd ~ 2 m_i / dt, whatever the physics integrator does.
  HoldPolicy(const Model& model, const Eigen::VectorXd& q_ref, double kp, double kd,
             double step_dt = 0.0);
  // τ (size nu). Allocates nothing.
  void torque(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
              const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> tau) const;
};

// What the robot does when its controller goes silent (sim/README.md, "Controller loss"): past
// the last policy's end plus a grace period, a stand-down. The legs whose foot is on the ground
// hold the angles they have (the feet stay where they are: pulling planted feet towards a default
// stance would fight the closed chain through the ground), the other joints (legs in swing, the
// arms) move linearly to the default posture over `ramp` seconds, and the last policy's
// feed-forward (the torques that carried the robot's weight) fades out over the same time while
// the PD takes the load. Then the PD alone, until a controller is back.
struct StandDownOptions {
  double grace = 0.05;  // [s] past the policy's end: its last knot held (a late answer)
  double ramp = 0.3;    // [s] for the swinging legs to reach the default posture
};

class StandDown {
 public:
  // hold: the PD and the default posture; contact_frames: the robot's contacts, in the order of
  // begin()'s mask. Allocates.
  StandDown(const Model& model, const HoldPolicy& hold, const std::vector<int>& contact_frames,
            const StandDownOptions& options);

  const StandDownOptions& options() const { return options_; }
  // Starts at time t from configuration q, with u_last the feed-forward the robot was applying
  // and bit c of `on_ground` set when contact c carries load. Allocates nothing.
  void begin(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
             const Eigen::Ref<const Eigen::VectorXd>& u_last, unsigned on_ground);
  // τ (size nu) at time t ≥ the start. Allocates nothing.
  void torque(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
              const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> tau) const;

 private:
  const Model& model_;
  const HoldPolicy& hold_;
  StandDownOptions options_;
  std::vector<unsigned> chains_;  // per actuated joint: bit c when it moves contact c's frame
  std::vector<char> planted_;     // per actuated joint: holds its angle (its foot is down)
  double t0_ = 0.0;
  Eigen::VectorXd q_start_, u_start_;
};

}  // namespace stride::sim
