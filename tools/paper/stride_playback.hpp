#pragma once
// The large-stride experiment's DDP motion played on the mock robot (the paper's §V-A: "the
// motion is executed"): the planning is large_stride.hpp, this is the playback, one idea a file.

#include <array>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "sim/disturbances.hpp"
#include "tools/paper/large_stride.hpp"

namespace stride {

// The DDP motion played on the mock robot through stride-sim's node (sim::SimNode: policy
// decoding and validation, interpolation, torque clamping, contacts from the sole corners on flat
// ground, unilateral Coulomb friction, plastic impacts, 1 ms steps), in lock-step over an
// in-process LCM bus: the node publishes a state estimate, the playback answers it with a
// policy_t, τ = u + K (x_ref ⊖ x), cut from one time-varying policy computed offline, and the
// node steps until the next estimate. Then the robot stands on the final sample for `hold_s`.
// Fell: base tilt over 45° or base below half its start height.
//
// The playback policy (StrideSimOptions::tvlqr): feed-forward and reference the DDP solution's
// (u = us, x_ref = xs), gains from a time-varying LQR around it: the plan's problem rebuilt with
// stiffer state tracking (x ⊖ xs, the other terms as offline), its derivatives at (xs, us) and one
// backward pass, no forward pass. Without tvlqr, the gains of the offline solve's last backward
// pass (the paper's regularization weights).
struct StrideSimResult {
  bool fell = false;
  double fall_time = -1.0;
  bool completed = false;  // no fall, both feet down at the end, base within 10 cm of the plan's
  std::array<double, 2> peak_normal_force{0.0, 0.0};  // raw, per 1 ms step
  // Peak of each foot's normal force averaged over the knot period (the plan's resolution).
  std::array<double, 2> peak_normal_force_knot{0.0, 0.0};
  double max_base_error = 0.0;  // |base position - plan| [m]
  double final_base_error = 0.0;
  double max_tilt_deg = 0.0;
  int clamped_steps = 0;
  // stride-sim's node: policies received and rejected, steps on its hold PD (no policy) and past
  // a policy's end, estimates the playback did not answer.
  long policies = 0, policies_rejected = 0, hold_steps = 0, exhausted_steps = 0, unanswered = 0;
  double lqr_time_s = 0.0;  // the planned stop and the TVLQR gains (derivatives + backward pass)
  double stop_gap = 0.0;    // the planned stop's dynamic infeasibility after its iterations
  // Per knot period: time, mean normal force per foot, base x, base z.
  std::vector<std::array<double, 5>> trace;
  // Per 1 ms step when asked for (record_steps): the columns of stepColumns().
  std::vector<std::vector<double>> steps;
  static const std::vector<std::string>& stepColumns();
};
struct StrideSimOptions {
  double hold_s = 1.0;  // standing after the plan's end
  // TVLQR gains (false: the offline solve's). The state weights of the tracking problem
  // (joints, base orientation, velocities on x ⊖ xs; the base position is left to the CoM and
  // feet terms) and how far its horizon runs past the hold, so that the gains of the hold are
  // those of standing still rather than of a horizon about to end.
  bool tvlqr = true;
  double w_track_posture = 10.0, w_track_base_orientation = 10.0, w_track_velocity = 1.0;
  double lqr_tail_s = 1.0;
  int stop_iterations = 50;  // box-FDDP iterations of the stop (the standing after the walk)
  // The policy's velocity reference at the knots' middles (semi-implicit Euler knots; see
  // fillPolicy in large_stride.cpp) instead of at the knots. Not with Rk4 knots, whose v_{k+1}
  // is the velocity at t_{k+1} (stride-paper-large-stride turns it off for them).
  bool midpoint = true;
  // Lock-step: estimates per second of sim time, and the knots of each answer (from the policy
  // knot at or before the estimate's time; they must cover the time to the next estimate).
  double state_rate_hz = 50.0;
  int answer_knots = 6;
  sim::PushSchedule pushes;  // shoves on the base (robustness of the playback; none by default)
  bool record_steps = false;
};
StrideSimResult simulateStrides(const Robot& robot, StrideProblem& sp, const StrideSolve& solve,
                                const StrideSimOptions& options = {});

}  // namespace stride
