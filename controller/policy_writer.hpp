#pragma once
// What the controller's answers are on the wire (ARCHITECTURE.md §1 step 5, §5): the policy the
// robot applies, τ = u_ff + K (x_ref ⊖ x) per knot, in its three forms (a solve's, the previous
// one advanced in time, the hold), and the predicted horizon a viewer draws. The tick
// (controller/mpc.hpp) decides which answer goes out; this writes it, in the shapes the messages
// were given at construction, so that nothing allocates (msg::shape).

#include <cstdint>

#include "config/robot_config.hpp"
#include "locomotion/planner.hpp"
#include "messages/validate.hpp"
#include "solver/ddp/solver.hpp"

namespace stride {

enum PolicyStatus : std::int8_t {
  kPolicySolved = 0,
  kPolicyDeadline = 1,
  kPolicyPrevious = 2,
  kPolicyHold = 3,
  kPolicyNone = -1,
};

// Where a policy's knots start: the state it answers (stamp and plan time) and the tick.
struct PolicyStamp {
  std::int64_t utime = 0;
  double t = 0.0;
  std::int64_t tick = 0;
};

class PolicyWriter {
 public:
  // Policies of `knots` knots of dt for the robot (its model hash on each); the hold policy's
  // joint gains kp, kd (messages/hold_pd.hpp).
  PolicyWriter(const Robot& robot, int knots, double dt, double hold_kp, double hold_kd);

  const policy_t& policy() const { return policy_; }
  std::int64_t modelHash() const { return policy_.model_hash; }
  // The controller's identity on the policy channel (policy_t.source_id).
  void setSourceId(std::int64_t id) { policy_.source_id = previous_.source_id = id; }
  // The robot run the policies answer (policy_t.session).
  void setSession(std::int64_t session) { policy_.session = previous_.session = session; }
  // A new problem: no earlier policy is re-sent for it.
  void forgetPrevious() { have_previous_ = false; }
  bool hasPrevious() const { return have_previous_; }
  // The robot's clock moved by offset_us (Mpc::shiftClock): the previous policy's stamps with it.
  void shiftClock(std::int64_t offset_us);

  // The solver's trajectory: the first policy.knots *contact* knots (an impulse knot takes no time
  // and has no control; a horizon shorter than the policy holds its last knot), the gains the
  // solver's negated. Kept as the previous policy.
  void solved(const PolicyStamp& at, std::int32_t phase, std::int8_t status,
              const ShootingProblem& problem, const Solver& solver);
  // The previous policy advanced to utime (whole knots skipped): false, and nothing written, when
  // there is none or it has no knots left to interpolate.
  bool previous(std::int64_t utime, std::int64_t tick);
  // Joint PD to the default posture around the measured base x, with u_hold (the torques that
  // hold the default posture on the contacts of `phase`) as feed-forward.
  void hold(const PolicyStamp& at, unsigned phase, const Eigen::VectorXd& x,
            const Eigen::VectorXd& u_hold);

  // The whole predicted horizon of the last solve (the policy just written), into h shaped by
  // msg::shape(h, knots, nq, contacts, footholds): each knot's time, configuration, mode, contacts
  // and forces, and the footholds the planner chose (its touch-downs after the state's plan time
  // t_state, no later than the last knot, at most msg::kHorizonFootholdsPerContact each, by
  // contact then time). False, and nothing written, when the knots' forces are not the solution's
  // (Solver::dataAtSolution: a rejected trial's rollout came last).
  bool horizon(horizon_t& h, const Planner& planner, const Solver& solver, double t_state) const;

 private:
  const Robot& robot_;
  int nq_, nv_, nu_;
  double dt_, hold_kp_, hold_kd_;
  policy_t policy_, previous_;
  bool have_previous_ = false;
};

}  // namespace stride
