#include "solver/ddp/solver.hpp"

#include <cmath>
#include <limits>

namespace stride {

namespace {
// What a rollout that leaves the dynamics costs: the line search rejects it.
constexpr double kFailedRolloutCost = std::numeric_limits<double>::infinity();
}  // namespace

bool Solver::rollout() {
  // Into the trial trajectory, swapped in only when every knot succeeded: a failure keeps the
  // last good iterate.
  xs_try_[0] = problem_.x0();
  double cost = 0.0;
  for (int k = 0; k < T_; ++k) {
    us_try_[k] = us_[k];
    if (has_bounds_ && kind_ == SolverKind::BoxFddp) {
      const int nu = problem_.nu(k);
      us_try_[k] = us_try_[k].cwiseMax(u_lower_.head(nu)).cwiseMin(u_upper_.head(nu));
    }
    ActionData& d = problem_.data(k);
    problem_.knot(k).calc(d, xs_try_[k], us_try_[k]);
    if (d.status != KnotStatus::Ok) return false;
    cost += d.cost;
    xs_try_[k + 1] = d.x_next;
  }
  ActionData& dT = problem_.terminalData();
  problem_.terminal().calc(dT, xs_try_[T_], Eigen::VectorXd());
  if (dT.status != KnotStatus::Ok || !std::isfinite(cost + dT.cost)) return false;
  xs_.swap(xs_try_);
  us_.swap(us_try_);
  data_at_solution_ = true;
  cost_ = cost + dT.cost;
  for (auto& f : fs_) f.setZero();
  gap_ = tail_gap_ = 0.0;
  feasible_ = true;
  return true;
}

double Solver::computeGaps() {
  const StateSpace& state = problem_.state();
  state.difference(xs_[0], problem_.x0(), fs_[0]);
  tail_gap_ = 0.0;
  for (int k = 0; k < T_; ++k) {
    state.difference(xs_[k + 1], problem_.data(k).x_next, fs_[k + 1]);
    tail_gap_ += fs_[k + 1].lpNorm<1>();
  }
  return fs_[0].lpNorm<1>() + tail_gap_;
}

void Solver::predictChange() {
  // The step's first- and second-order cost change, d1 and d2, along the linearized rollout at
  // α = 1 (δx_0 = f_0, δu = k + K δx, δx⁺ = Fx δx + Fu δu + f): the cost's quadratic model at
  // step α then predicts α d1 + ½ α² d2, exact for linear dynamics and quadratic costs.
  d1_ = d2_ = 0.0;
  dx_ = fs_[0];
  for (int k = 0; k < T_; ++k) {
    const ActionData& d = problem_.data(k);
    const int nu = problem_.nu(k);
    auto du = du_.head(nu);
    du = k_[k];
    du.noalias() += K_[k] * dx_;
    d1_ += d.Lx.dot(dx_) + d.Lu.dot(du);
    tmp_x_.noalias() = d.Lxx * dx_;
    tmp_x_.noalias() += 2.0 * (d.Lxu * du);
    d2_ += dx_.dot(tmp_x_);
    w_.head(nu).noalias() = d.Luu * du;
    d2_ += du.dot(w_.head(nu));
    dx_next_ = fs_[k + 1];
    dx_next_.noalias() += d.Fx * dx_;
    dx_next_.noalias() += d.Fu * du;
    dx_.swap(dx_next_);
  }
  const ActionData& dT = problem_.terminalData();
  d1_ += dT.Lx.dot(dx_);
  tmp_x_.noalias() = dT.Lxx * dx_;
  d2_ += dx_.dot(tmp_x_);
}

double Solver::forwardPass(double alpha) {
  const PieceGuard piece{*this};
  ++forward_passes_;
  data_at_solution_ = false;  // the knots' data become the trial's (true again if accepted)
  const StateSpace& state = problem_.state();
  const bool box = kind_ == SolverKind::BoxFddp && has_bounds_;
  // x̂_0 = x_0 ⊕ α f_0, û = u + α k + K (x̂ ⊖ x), x̂⁺ = f(x̂, û) ⊕ (α - 1) f: the gaps shrink to
  // (1 - α) f (zero for a full step).
  tmp_x_ = alpha * fs_[0];
  state.integrate(xs_[0], tmp_x_, xs_try_[0]);
  double cost = 0.0;
  for (int k = 0; k < T_; ++k) {
    const int nu = problem_.nu(k);
    state.difference(xs_[k], xs_try_[k], dx_);
    Eigen::VectorXd& u = us_try_[k];
    u = us_[k] + alpha * k_[k];
    u.noalias() += K_[k] * dx_;
    if (box) u = u.cwiseMax(u_lower_.head(nu)).cwiseMin(u_upper_.head(nu));
    ActionData& d = problem_.data(k);
    problem_.knot(k).calc(d, xs_try_[k], u);
    if (d.status != KnotStatus::Ok) return kFailedRolloutCost;
    cost += d.cost;
    if (feasible_) {
      xs_try_[k + 1] = d.x_next;
    } else {
      tmp_x_ = (alpha - 1.0) * fs_[k + 1];
      state.integrate(d.x_next, tmp_x_, xs_try_[k + 1]);
    }
  }
  ActionData& dT = problem_.terminalData();
  problem_.terminal().calc(dT, xs_try_[T_], Eigen::VectorXd());
  if (dT.status != KnotStatus::Ok) return kFailedRolloutCost;
  cost += dT.cost;
  return std::isfinite(cost) ? cost : kFailedRolloutCost;
}
}  // namespace stride
