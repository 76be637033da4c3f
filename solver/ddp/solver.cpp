#include "solver/ddp/solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

// The iteration (solve, prepare) and its derivatives; the passes have files of their own:
// backward_pass.cpp, forward_pass.cpp (rollouts, line-search trials, predicted change) and
// warm_start.cpp (warm start, shift, retiming).

namespace stride {

namespace {
// μ never restarts from 0 when raised, so the retries of a failed backward pass are bounded.
constexpr double kRegFloor = 1e-9;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
}  // namespace

const char* toString(SolveStatus status) {
  switch (status) {
    case SolveStatus::Converged:
      return "converged";
    case SolveStatus::MaxIterations:
      return "iteration limit";
    case SolveStatus::Deadline:
      return "deadline";
    case SolveStatus::NoDescent:
      return "no descent (regularization limit)";
    case SolveStatus::NonFinite:
      return "non-finite value";
  }
  return "?";
}

Solver::Solver(ShootingProblem& problem, SolverKind kind, const SolverOptions& opts)
    : options(opts),
      problem_(problem),
      kind_(kind),
      T_(problem.horizon()),
      ndx_(problem.ndx()),
      box_(problem.maxNu()) {
  const int nx = problem.nx(), m = problem.maxNu(), n = ndx_;
  xs_.assign(T_ + 1, problem.x0());
  xs_try_ = xs_;
  fs_.assign(T_ + 1, Eigen::VectorXd::Zero(n));
  for (int k = 0; k < T_; ++k) {
    const int nu = problem.nu(k);
    us_.push_back(Eigen::VectorXd::Zero(nu));
    k_.push_back(Eigen::VectorXd::Zero(nu));
    K_.push_back(Eigen::MatrixXd::Zero(nu, n));
  }
  us_try_ = us_;
  K_old_ = K_;
  Vx_next_ = Vx_ = Vx_gap_ = Qx_ = Eigen::VectorXd::Zero(n);
  Vxx_next_ = Vxx_ = Qxx_ = VFx_ = Eigen::MatrixXd::Zero(n, n);
  Qxu_ = VFu_ = Eigen::MatrixXd::Zero(n, m);
  Quu_ = Quu_inv_ = Eigen::MatrixXd::Zero(m, m);
  VB_ = Eigen::MatrixXd::Zero(n, n / 2);
  BtY_ = Eigen::MatrixXd::Zero(n / 2, std::max(n, m));
  W_ = Wf_ = Eigen::MatrixXd::Zero(m, n);
  Qu_ = Eigen::VectorXd::Zero(m);
  w_ = Eigen::VectorXd::Zero(m);
  dx_ = dx_next_ = tmp_x_ = Eigen::VectorXd::Zero(n);
  du_ = Eigen::VectorXd::Zero(m);
  u_lower_ = Eigen::VectorXd::Constant(m, -kInfinity);
  u_upper_ = Eigen::VectorXd::Constant(m, kInfinity);
  stats_.resize(kMaxStats);
  reg_ = options.reg_initial;
  x_last_ = Eigen::VectorXd::Zero(nx);
  u_last_ = Eigen::VectorXd::Zero(problem.nu(T_ - 1));
  K_last_ = Eigen::MatrixXd::Zero(problem.nu(T_ - 1), n);
}

void Solver::setControlBounds(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  const int m = problem_.maxNu();
  if (lower.size() != m || upper.size() != m)
    throw std::invalid_argument("Solver::setControlBounds: bounds must have size " +
                                std::to_string(m));
  if ((lower.array() > upper.array()).any())
    throw std::invalid_argument("Solver::setControlBounds: a lower bound exceeds its upper bound");
  u_lower_ = lower;
  u_upper_ = upper;
  has_bounds_ = true;
}

bool Solver::finiteTrajectory() const {
  for (const auto& x : xs_)
    if (!x.allFinite()) return false;
  for (const auto& u : us_)
    if (!u.allFinite()) return false;
  return true;
}

bool Solver::computeDerivatives(Clock::time_point deadline) {
  derive_next_ = 0;
  return derivatives(deadline);
}

bool Solver::derivatives(Clock::time_point deadline) {
  cut_ = false;
  // In chunks of knots from derive_next_ (knot index T_: the terminal one), the deadline checked
  // between them; a cut one resumes there.
  const int chunk = kDeadlineKnots * problem_.threads();
  double cost = 0.0;
  while (derive_next_ <= T_) {
    const Clock::time_point start = Clock::now();
    const int end = std::min(derive_next_ + chunk, T_ + 1);
    cost = problem_.calcDiff(xs_, us_, derive_next_, end);  // the total over all knots
    pieceDone(start);
    derive_next_ = end;
    if (derive_next_ <= T_ && Clock::now() >= deadline) {
      cut_ = true;
      return false;
    }
  }
  data_at_solution_ = true;  // every knot derived at xs_
  const PieceGuard piece{*this};
  const double gap = computeGaps();
  if (!std::isfinite(cost) || !std::isfinite(gap)) return false;
  cost_ = cost;
  gap_ = gap;
  feasible_ = gap_ < options.gap_tolerance;
  return true;
}

bool Solver::prepare(Clock::time_point deadline, SolveStatus& status) {
  const Clock::time_point start = Clock::now();
  if (!preparing_) {  // a new preparation; else the one a deadline cut resumes where it stopped
    prepared_ = false;
    preparing_ = true;
    derived_ = false;
    derive_next_ = 0;
    backward_next_ = -1;
    backward_passes_ = 0;
    prepare_ms_ = 0.0;
  }
  const auto stop = [&](SolveStatus why) {
    prepare_ms_ += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (why != SolveStatus::Deadline) {
      preparing_ = false;
      why = fail(why);
    }
    status = why;
    return false;
  };
  if (start >= deadline) return stop(SolveStatus::Deadline);
  if (!derived_) {
    if (derive_next_ == 0 && !finiteTrajectory()) return stop(SolveStatus::NonFinite);
    if (!derivatives(deadline)) return stop(cut_ ? SolveStatus::Deadline : SolveStatus::NonFinite);
    derived_ = true;
  }
  // A Quu that is not positive definite: more regularization, until the limit or the deadline.
  // From μ = 0 the first raise goes to kRegFloor, so the retries are bounded.
  while (!backward(deadline)) {
    if (cut_) return stop(SolveStatus::Deadline);
    if (backward_nonfinite_) return stop(SolveStatus::NonFinite);
    reg_ = std::max(reg_ * options.reg_factor, kRegFloor);
    if (reg_ > options.reg_max) return stop(SolveStatus::NoDescent);
    if (Clock::now() >= deadline) {
      // The retry starts at the next call, with the raised μ.
      status = SolveStatus::Deadline;
      prepare_ms_ += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      return false;
    }
  }
  prepare_ms_ += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  preparing_ = false;
  prepared_ = true;
  return true;
}

SolveStatus Solver::solve(int max_iterations, Clock::time_point deadline) {
  iterations_ = 0;
  forward_passes_ = 0;
  if (!prepared_ && !preparing_) backward_passes_ = 0;  // else they count the preparation's
  if (kind_ == SolverKind::Ddp) {
    discardPreparation();  // the rollout from x0 moves the trajectory the preparation linearized
    if (!rollout()) return fail(SolveStatus::NonFinite);
  }
  if (!finiteTrajectory()) return fail(SolveStatus::NonFinite);
  for (int it = 0; it < max_iterations; ++it) {
    SolveStatus status = SolveStatus::MaxIterations;
    if (!prepared_ && !prepare(deadline, status)) return status;
    const Clock::time_point start = Clock::now();
    if (start >= deadline) return SolveStatus::Deadline;  // the preparation stays for the next
    // The preparation is used once: the step below moves the trajectory it linearized.
    prepared_ = false;
    IterationStats s;
    s.iteration = it;
    // x0 enters here and only here: the gap f_0 (the backward pass reads f_1 ... f_T), and with
    // it the feasibility and the predicted change of the step.
    problem_.state().difference(xs_[0], problem_.x0(), fs_[0]);
    gap_ = fs_[0].lpNorm<1>() + tail_gap_;
    feasible_ = gap_ < options.gap_tolerance;
    predictChange();
    s.stop = std::abs(d1_);
    const bool converged = s.stop < options.stop_tolerance && feasible_;
    double alpha = 1.0;
    bool accepted = false, out_of_time = false;
    Clock::duration trial{0};  // the last trial's duration: the next one's expected
    for (int i = 0; !converged && i < options.line_search_steps; ++i, alpha *= 0.5) {
      // A trial that would end after the deadline is not started: the answer stays on time.
      const Clock::time_point trial_start = Clock::now();
      if (trial_start + trial >= deadline) {
        out_of_time = true;
        break;
      }
      const double cost_try = forwardPass(alpha);
      trial = Clock::now() - trial_start;
      const double expected = expectedCostChange(alpha);
      const double actual = cost_try - cost_;
      // A predicted decrease must be realized at least in part (Armijo-like); closing gaps may
      // raise the cost, by at most twice the prediction.
      const double slack = 1e-12 * std::max(1.0, std::abs(cost_));
      const bool ok = std::isfinite(cost_try) &&
                      (expected < 0.0 ? actual <= options.accept_ratio * expected + slack
                                      : actual <= 2.0 * expected + slack);
      if (ok) {
        accepted = true;
        xs_.swap(xs_try_);
        us_.swap(us_try_);
        data_at_solution_ = true;
        s.expected = expected;
        s.actual = actual;
        cost_ = cost_try;
        if (!feasible_) {
          for (auto& f : fs_) f *= (1.0 - alpha);
          gap_ *= (1.0 - alpha);
          feasible_ = alpha == 1.0 || gap_ < options.gap_tolerance;
        }
        break;
      }
    }
    // μ adapts to the step taken; a line search cut short by the deadline says nothing about μ.
    if (accepted) {
      if (alpha >= options.step_decrease_reg)
        reg_ = std::max(reg_ / options.reg_factor, options.reg_min);
      else if (alpha <= options.step_increase_reg)
        reg_ = std::min(reg_ * options.reg_factor, options.reg_max);
    } else if (!converged && !out_of_time) {
      reg_ = std::max(reg_ * options.reg_factor, kRegFloor);
    }
    s.step = accepted ? alpha : 0.0;
    s.cost = cost_;
    s.gap = gap_;
    s.regularization = reg_;
    s.time_ms =
        prepare_ms_ + std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (iterations_ < kMaxStats) stats_[iterations_] = s;
    ++iterations_;
    if (callback) callback(s);
    if (converged) return SolveStatus::Converged;
    if (out_of_time || Clock::now() >= deadline) return SolveStatus::Deadline;
    if (!accepted && reg_ > options.reg_max) return fail(SolveStatus::NoDescent);
  }
  return SolveStatus::MaxIterations;
}

// After a failure μ starts again from its initial value: it carries over between solves, and a
// stuck 1e9 would cripple the next ones.
SolveStatus Solver::fail(SolveStatus status) {
  reg_ = options.reg_initial;
  return status;
}

void Solver::printIterationTable(const IterationStats& s) {
  if (s.iteration % 10 == 0)
    std::printf("%5s %14s %11s %11s %11s %9s %9s %9s\n", "iter", "cost", "gap", "stop", "expected",
                "step", "reg", "ms");
  std::printf("%5d %14.8e %11.3e %11.3e %11.3e %9.4f %9.1e %9.3f\n", s.iteration, s.cost, s.gap,
              s.stop, s.expected, s.step, s.regularization, s.time_ms);
}

}  // namespace stride
