#pragma once
// DDP over a shooting problem (paper §III, eq. 12), in three variants that share one iteration:
//   Ddp      the paper's DDP: the warm start is first rolled out from x0, so the trajectory is
//            dynamically feasible and stays so;
//   Fddp     feasibility-driven DDP (Mastalli et al. 2020): the warm start (xs, us) is kept as
//            given, gaps f_{k+1} = f(x_k, u_k) ⊖ x_{k+1} included, and a step of length α closes
//            the fraction α of every gap, so a shifted trajectory is a valid warm start;
//   BoxFddp  Fddp with bounds on the controls (torque limits): each knot's control step is a box
//            QP solved by projected Newton, the gains act on the free controls only, and the
//            rollout clamps the controls.
// With zero gaps the Fddp iteration is exactly DDP, which is why one iteration serves all three.
//
// One iteration: calcDiff of every knot (parallel) → backward Riccati pass with Gauss-Newton Q
// terms, Levenberg-Marquardt regularization μ on Quu and μ on Vxx (Tassa, Erez & Todorov 2012) →
// expected cost change of the step from a linearized rollout → backtracking line search from
// α = 1 on the nonlinear rollout → μ adapted (down after long steps, up after short or failed
// ones).
//
// The iteration splits where the initial state x0 enters (real-time iteration, Diehl et al.
// 2005): the derivatives and the backward pass read the trajectory and the gaps f_1 ... f_T, never
// x0, which only sets the gap f_0 the step starts with. prepare() does the first half ahead of
// time; the next solve() sets f_0 from the x0 of that moment and goes straight to the line search.
// A controller prepares after publishing and so answers a new state with a rollout only.
//
// After construction nothing allocates: solve() works in preallocated trajectories and
// workspaces and never throws; a non-finite value stops it with a status, keeping the last good
// iterate.

#include <algorithm>
#include <chrono>
#include <functional>
#include <vector>

#include "solver/ddp/box_qp.hpp"
#include "solver/ocp/problem.hpp"

namespace stride {

enum class SolverKind : std::uint8_t { Ddp, Fddp, BoxFddp };

enum class SolveStatus : std::uint8_t {
  Converged,      // expected improvement and gaps below the tolerances
  MaxIterations,  // the iteration budget ran out (the iterate is still the best found)
  Deadline,       // stopped for the deadline (idem): passed, or a trial would have passed it
  NoDescent,      // no step length decreased the cost, even at the largest regularization
  NonFinite,      // a knot returned a non-finite value or failed; the last good iterate kept
};
const char* toString(SolveStatus status);

struct IterationStats {
  int iteration = 0;
  double cost = 0.0;      // after the step
  double gap = 0.0;       // Σ |f_k|₁ after the step
  double expected = 0.0;  // predicted cost change of the accepted step (negative: decrease)
  double actual = 0.0;    // actual cost change
  double stop = 0.0;      // |first-order expected change| before the step
  double step = 0.0;      // α accepted (0: none)
  double regularization = 0.0;
  double time_ms = 0.0;  // wall time of the iteration
};

struct SolverOptions {
  double stop_tolerance = 1e-9;  // on |d1|, the first-order expected cost change
  double gap_tolerance = 1e-9;   // Σ |f_k|₁ below which the trajectory counts as feasible
  double accept_ratio = 0.1;     // accept a step when the actual change ≥ ratio × expected
  double reg_initial = 1e-9, reg_min = 1e-9, reg_max = 1e9, reg_factor = 10.0;
  double step_decrease_reg = 0.5;   // α ≥ this: μ /= factor
  double step_increase_reg = 0.01;  // α ≤ this: μ *= factor
  int line_search_steps = 10;       // α = 1, 1/2, ..., 2^-(steps-1)
  // Use the Euler structure of Fx, Fu where knots provide it (action.hpp); off only to compare
  // with the dense products in tests.
  bool exploit_structure = true;
  // Told of each piece of work as it ends (not owned; null: none).
  class WorkHook* work_hook = nullptr;
};

// Told of each piece of an iteration's work as it ends, with the time it started: a chunk of
// derivatives or of the backward pass (kDeadlineKnots knots per thread), the gaps, a rollout. The
// overload tests stretch the pieces with it to play a slower host (controller/slow_host.hpp):
// the solver itself only reports.
class WorkHook {
 public:
  virtual ~WorkHook() = default;
  virtual void pieceDone(std::chrono::steady_clock::time_point started) = 0;
};

class Solver {
 public:
  using Clock = std::chrono::steady_clock;

  // options.reg_initial is the first μ; μ then carries over between solves and restarts from it
  // after a failed solve.
  Solver(ShootingProblem& problem, SolverKind kind = SolverKind::Fddp,
         const SolverOptions& options = SolverOptions());

  SolverKind kind() const { return kind_; }
  SolverOptions options;

  // Control bounds of every knot for BoxFddp (size maxNu; ±infinity allowed). Throws
  // std::invalid_argument for wrong sizes or lower > upper. Setup only.
  void setControlBounds(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

  // Warm start (copied, no allocation): xs has T + 1 states, us T controls. False (and nothing
  // changed) on wrong sizes or non-finite values. Without a warm start: x0 everywhere, u = 0.
  bool setWarmStart(const std::vector<Eigen::VectorXd>& xs, const std::vector<Eigen::VectorXd>& us);
  // Shifts the current trajectory by n knots for the next receding-horizon solve: x_k <- x_{k+n},
  // u_k <- u_{k+n}, the tail repeating the last state and control. (Call problem.shift(n) too.)
  void shiftWarmStart(int n);
  // Moves the current trajectory onto a new time grid (the horizon moved by a few short knots of a
  // non-uniform grid, or an impulse knot came in): from[k], to[k] are the times of knot k on the
  // old and the new grid (T + 1 each, non-decreasing; two knots at one time are an impulse knot
  // and the knot after it). New knot k takes the old trajectory at its time: the old knot's state,
  // control and gain where one is at that time (for the second of two knots at one time, the
  // post-impact one); between two old knots, the state interpolated on the manifold and the
  // control linearly with the same weight, the gain of the nearer knot (a control taken from the
  // knot before while the state comes mostly from the knot after grew a perturbation by 2x per
  // tick in the receding horizon); past the old end, the last ones. No allocation.
  void retimeWarmStart(const std::vector<double>& from, const std::vector<double>& to);
  // Replaces the warm start's control of knot k (copied, no allocation; false and nothing changed
  // for a knot or size out of range or a non-finite u).
  bool setControl(int k, const Eigen::VectorXd& u);

  // Iterates from the current trajectory until converged, max_iterations, or the deadline (a
  // line-search trial is not started when one as long as the last would end after it). The
  // first iteration uses a pending preparation (Fddp and BoxFddp; Ddp's rollout from x0 moves the
  // trajectory, so it discards it).
  SolveStatus solve(int max_iterations, Clock::time_point deadline = Clock::time_point::max());

  // The first half of the next iteration: derivatives and backward pass at the current trajectory
  // and μ. True when done; false, with the reason in status (Deadline, NonFinite, NoDescent),
  // when not. Until the next solve() only x0 may change: anything else that changes the problem
  // (shift, references, phases) must be followed by discardPreparation(); setWarmStart and
  // shiftWarmStart discard it themselves.
  // A preparation its deadline cut (Deadline) is resumed where it stopped by the next prepare()
  // or solve(), unless discarded before (controller/README.md, "Overload").
  bool prepare(Clock::time_point deadline, SolveStatus& status);
  bool prepared() const { return prepared_; }
  // The problem's knot data (costs, contact forces) were last computed at xs()/us(), for the
  // problem as it is: after a rollout, complete derivatives or an accepted trial; not after a
  // rejected trial (whose rollout they then hold) nor after a change that discarded the
  // preparation. Viewers read the planned forces then (controller: horizon_t).
  bool dataAtSolution() const { return data_at_solution_; }
  bool preparing() const { return preparing_; }         // a preparation was cut and may resume
  double prepareMillis() const { return prepare_ms_; }  // of the last one, its resumed parts summed
  void discardPreparation() {
    prepared_ = false;
    preparing_ = false;
    data_at_solution_ = false;
  }

  const std::vector<Eigen::VectorXd>& xs() const { return xs_; }
  const std::vector<Eigen::VectorXd>& us() const { return us_; }
  // Feedback policy of the last backward pass: u_k = us_k + K_k (x ⊖ xs_k) (ARCHITECTURE §3).
  const std::vector<Eigen::MatrixXd>& K() const { return K_; }
  const std::vector<Eigen::VectorXd>& k() const { return k_; }  // feed-forward step
  double cost() const { return cost_; }
  double gap() const { return gap_; }
  // μ carries over between solves (a receding horizon meets similar problems); it starts at
  // options.reg_initial.
  double regularization() const { return reg_; }
  void setRegularization(double mu) { reg_ = mu; }
  int iterations() const { return iterations_; }
  // Backward passes (regularization retries included) and nonlinear rollouts (line-search trials)
  // of the last solve, the backward passes of a preparation it used included: what an iteration
  // really cost.
  int backwardPasses() const { return backward_passes_; }
  int forwardPasses() const { return forward_passes_; }
  // Statistics of the iterations of the last solve (capacity fixed at construction).
  static constexpr int kMaxStats = 1000;
  const IterationStats* stats() const { return stats_.data(); }
  int statsCount() const { return std::min(iterations_, kMaxStats); }

  // Called after every iteration (set at setup; the call itself does not allocate, the callback
  // might). printIterationTable is a ready-made one.
  std::function<void(const IterationStats&)> callback;
  static void printIterationTable(const IterationStats& s);

  // The pieces of an iteration, public for the benchmarks (knots/<robot>/{backward,forward}):
  // calcDiff of all knots and the gaps (false, and the iterate's cost kept, when a value is not
  // finite); the backward pass at regularization μ (false when a Quu is not positive definite or
  // a value is not finite); the nonlinear rollout at step α into the trial trajectory (returns its
  // cost); the cost change the quadratic model of the last backward pass predicts for step α,
  // once predictChange() has run the linearized rollout from the current gap f_0.
  // The first two stop, false with cutAtDeadline(), at the first check after the deadline: they
  // check it every kDeadlineKnots knots (per thread), so that an overrun costs a few knots'
  // work, not a whole pass (controller/README.md, "Overload").
  static constexpr int kDeadlineKnots = 8;
  bool computeDerivatives(Clock::time_point deadline = Clock::time_point::max());
  bool backwardPass(Clock::time_point deadline = Clock::time_point::max());
  bool cutAtDeadline() const { return cut_; }  // (a cut pass is not resumed by these two)
  double forwardPass(double alpha);
  void predictChange();  // d1, d2 from the linearized rollout of the step
  double expectedCostChange(double alpha) const { return alpha * (d1_ + 0.5 * alpha * d2_); }

 private:
  bool rollout();  // xs from x0 and us (Ddp's feasible start); false (iterate kept) on failure
  // computeDerivatives and backwardPass from where a deadline cut them (derive_next_,
  // backward_next_ < 0: a new pass).
  bool derivatives(Clock::time_point deadline);
  bool backward(Clock::time_point deadline);
  SolveStatus fail(SolveStatus status);
  double computeGaps();  // f_k of the current trajectory from the knots' x_next; Σ |f|₁
  bool finiteTrajectory() const;
  void eulerProducts(const ActionData& d, int nu);  // Qxx, Qxu, Quu of an Euler knot

  ShootingProblem& problem_;
  SolverKind kind_;
  int T_, ndx_;
  std::vector<Eigen::VectorXd> xs_, us_, xs_try_, us_try_;
  std::vector<Eigen::VectorXd> fs_;  // gaps f_0 = x0 ⊖ x_0, f_{k+1} = f(x_k, u_k) ⊖ x_{k+1}
  // Per knot only what the forward pass reads: the policy.
  std::vector<Eigen::VectorXd> k_;
  std::vector<Eigen::MatrixXd> K_, K_old_;  // K_old_: retimeWarmStart's copy
  // Value function of the knot after the current one and of the current one (rolling buffers).
  Eigen::VectorXd Vx_next_, Vx_, Vx_gap_;
  Eigen::MatrixXd Vxx_next_, Vxx_;
  // Riccati workspaces of the current knot (the pass is serial: one set for all knots).
  Eigen::VectorXd Qx_, Qu_;
  Eigen::MatrixXd Qxx_, Qxu_, Quu_, Quu_inv_, VFx_, VFu_, W_, Wf_;
  Eigen::VectorXd w_;
  Eigen::MatrixXd VB_, BtY_;  // Euler-structure products
  // Linearized rollout.
  Eigen::VectorXd dx_, dx_next_, du_, tmp_x_;
  BoxQP box_;  // one workspace: the backward pass is serial
  Eigen::VectorXd u_lower_, u_upper_;
  Eigen::VectorXd x_last_, u_last_;  // shiftWarmStart's saved tail
  Eigen::MatrixXd K_last_;
  bool has_bounds_ = false;
  bool backward_nonfinite_ = false;
  bool cut_ = false;  // the last computeDerivatives / backwardPass stopped at its deadline
  // A preparation in progress (cut by its deadline): derivatives done up to derive_next_ (all:
  // derived_), the backward pass at backward_next_.
  bool preparing_ = false, derived_ = false;
  int derive_next_ = 0, backward_next_ = -1;
  bool feasible_ = false;
  bool prepared_ = false;  // derivatives and backward pass done for the next iteration
  bool data_at_solution_ = false;
  // options.work_hook told of a piece of work that started at `started`.
  void pieceDone(Clock::time_point started) const {
    if (options.work_hook) options.work_hook->pieceDone(started);
  }
  struct PieceGuard {  // pieceDone at the end of the scope
    const Solver& solver;
    Clock::time_point start = Clock::now();
    ~PieceGuard() { solver.pieceDone(start); }
  };
  double prepare_ms_ = 0.0;
  double cost_ = 0.0, gap_ = 0.0, d1_ = 0.0, d2_ = 0.0, reg_ = 0.0;
  double tail_gap_ = 0.0;  // Σ_{k ≥ 1} |f_k|₁: the gaps the backward pass reads
  int iterations_ = 0;
  int backward_passes_ = 0, forward_passes_ = 0;
  std::vector<IterationStats> stats_;
};

}  // namespace stride
