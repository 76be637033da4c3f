#include "solver/ddp/solver.hpp"

#include <algorithm>
#include <cmath>

namespace stride {

bool Solver::setWarmStart(const std::vector<Eigen::VectorXd>& xs,
                          const std::vector<Eigen::VectorXd>& us) {
  if (static_cast<int>(xs.size()) != T_ + 1 || static_cast<int>(us.size()) != T_) return false;
  for (int k = 0; k <= T_; ++k)
    if (xs[k].size() != problem_.nx() || !xs[k].allFinite()) return false;
  for (int k = 0; k < T_; ++k)
    if (us[k].size() != problem_.nu(k) || !us[k].allFinite()) return false;
  for (int k = 0; k <= T_; ++k) xs_[k] = xs[k];
  for (int k = 0; k < T_; ++k) us_[k] = us[k];
  feasible_ = false;
  discardPreparation();
  return true;
}

void Solver::shiftWarmStart(int n) {
  n = std::clamp(n, 0, T_);
  if (n == 0) return;
  // The new tail repeats the last state, control and gain of the old trajectory (saved first: a
  // shift by T rotates nothing).
  x_last_ = xs_[T_];
  const bool uniform = us_[T_ - 1].size() == u_last_.size();
  if (uniform) {
    u_last_ = us_[T_ - 1];
    K_last_ = K_[T_ - 1];
  }
  // Rotations swap the vectors' buffers: no allocation.
  std::rotate(xs_.begin(), xs_.begin() + n % (T_ + 1), xs_.end());
  std::rotate(us_.begin(), us_.begin() + n % T_, us_.end());
  std::rotate(K_.begin(), K_.begin() + n % T_, K_.end());
  std::rotate(k_.begin(), k_.begin() + n % T_, k_.end());
  for (int k = T_ + 1 - n; k <= T_; ++k) xs_[k] = x_last_;
  for (int k = T_ - n; k < T_; ++k)
    if (uniform && us_[k].size() == u_last_.size()) {
      us_[k] = u_last_;
      K_[k] = K_last_;
    }
  feasible_ = false;
  discardPreparation();
}

void Solver::retimeWarmStart(const std::vector<double>& from, const std::vector<double>& to) {
  if (static_cast<int>(from.size()) != T_ + 1 || static_cast<int>(to.size()) != T_ + 1) return;
  constexpr double eps = 1e-9;  // grid times are sums of durations: equal up to rounding
  bool same = true;
  for (int k = 0; k <= T_ && same; ++k) same = std::abs(from[k] - to[k]) <= eps;
  if (same) return;
  // The old trajectory goes to the line search's buffers (rewritten by every rollout).
  for (int k = 0; k <= T_; ++k) xs_try_[k] = xs_[k];
  for (int k = 0; k < T_; ++k) {
    us_try_[k] = us_[k];
    K_old_[k] = K_[k];
  }
  const StateSpace& space = problem_.state();
  const auto control = [&](int k, int j) {  // new knot k takes old knot j's control and gain
    j = std::min(j, T_ - 1);
    if (k < T_ && us_[k].size() == us_try_[j].size()) {
      us_[k] = us_try_[j];
      K_[k] = K_old_[j];
    }
  };
  int j = 0;  // the first old knot at or after the new knot's time
  for (int k = 0; k <= T_; ++k) {
    const double t = to[k];
    while (j <= T_ && from[j] < t - eps) ++j;
    if (j > T_) {  // past the old end
      xs_[k] = xs_try_[T_];
      control(k, T_ - 1);
    } else if (from[j] <= t + eps) {  // an old knot at this time
      int src = j;
      if (k > 0 && to[k] - to[k - 1] <= eps)  // after an impulse knot: the post-impact state
        while (src < T_ && from[src + 1] <= t + eps) ++src;
      xs_[k] = xs_try_[src];
      control(k, src);
    } else if (j == 0) {  // before the old start
      xs_[k] = xs_try_[0];
      control(k, 0);
    } else {  // between old knots a = j - 1 (the post-impact one of a pair) and j
      const int a = j - 1;
      const double s = (t - from[a]) / (from[j] - from[a]);
      space.difference(xs_try_[a], xs_try_[j], dx_);
      dx_ *= s;
      space.integrate(xs_try_[a], dx_, xs_[k]);
      control(k, s < 0.5 ? a : j);
      if (k < T_ && j < T_ && us_[k].size() == us_try_[a].size() &&
          us_[k].size() == us_try_[j].size())
        us_[k] = (1.0 - s) * us_try_[a] + s * us_try_[j];
    }
  }
  feasible_ = false;
  discardPreparation();
}

bool Solver::setControl(int k, const Eigen::VectorXd& u) {
  if (k < 0 || k >= T_ || u.size() != us_[k].size() || !u.allFinite()) return false;
  us_[k] = u;
  feasible_ = false;
  discardPreparation();
  return true;
}

}  // namespace stride
