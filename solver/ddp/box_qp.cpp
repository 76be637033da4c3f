#include "solver/ddp/box_qp.hpp"

#include <cmath>

namespace stride {

BoxQP::BoxQP(int n)
    : n_(n),
      free_(Eigen::VectorXi::Zero(n)),
      Hff_(Eigen::MatrixXd::Zero(n, n)),
      grad_(Eigen::VectorXd::Zero(n)),
      dx_(Eigen::VectorXd::Zero(n)),
      xtry_(Eigen::VectorXd::Zero(n)),
      Hx_(Eigen::VectorXd::Zero(n)),
      rhs_(Eigen::VectorXd::Zero(n)),
      xcur_(Eigen::VectorXd::Zero(n)) {}

double BoxQP::objective(const Eigen::Ref<const Eigen::MatrixXd>& H,
                        const Eigen::Ref<const Eigen::VectorXd>& g, const Eigen::VectorXd& x) {
  Hx_.noalias() = H * x;
  return 0.5 * x.dot(Hx_) + g.dot(x);
}

bool BoxQP::factorFree(const Eigen::Ref<const Eigen::MatrixXd>& H) {
  for (int a = 0; a < nfree_; ++a)
    for (int b = 0; b <= a; ++b) Hff_(a, b) = H(free_[a], free_[b]);
  if (nfree_ == 0) return true;
  Eigen::Ref<Eigen::MatrixXd> block(Hff_.topLeftCorner(nfree_, nfree_));
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(block);  // in place
  return llt.info() == Eigen::Success;
}

bool BoxQP::solve(const Eigen::Ref<const Eigen::MatrixXd>& H,
                  const Eigen::Ref<const Eigen::VectorXd>& g,
                  const Eigen::Ref<const Eigen::VectorXd>& lb,
                  const Eigen::Ref<const Eigen::VectorXd>& ub, Eigen::Ref<Eigen::VectorXd> x) {
  constexpr int kMaxIterations = 50;
  constexpr double kGradientTolerance = 1e-10, kArmijo = 0.1, kMinStep = 1e-12;
  xcur_ = x.cwiseMax(lb).cwiseMin(ub);
  iterations_ = 0;
  double value = objective(H, g, xcur_);
  for (; iterations_ < kMaxIterations; ++iterations_) {
    grad_ = g + Hx_;  // Hx_ holds H xcur_ from the last objective()
    // A variable is clamped when it sits on a bound and the gradient pushes it outwards.
    nfree_ = 0;
    for (int i = 0; i < n_; ++i) {
      const bool clamped =
          (xcur_[i] <= lb[i] && grad_[i] > 0.0) || (xcur_[i] >= ub[i] && grad_[i] < 0.0);
      if (!clamped) free_[nfree_++] = i;
    }
    if (nfree_ == 0) break;
    double gnorm = 0.0;
    for (int a = 0; a < nfree_; ++a) gnorm = std::max(gnorm, std::abs(grad_[free_[a]]));
    if (gnorm < kGradientTolerance) break;
    if (!factorFree(H)) return false;
    // Newton step on the free set, zero on the clamped one.
    auto step_f = rhs_.head(nfree_);
    for (int a = 0; a < nfree_; ++a) step_f[a] = -grad_[free_[a]];
    solveFree(step_f);
    dx_.setZero();
    for (int a = 0; a < nfree_; ++a) dx_[free_[a]] = step_f[a];
    // Projected backtracking: the projection may bend the step, so test the actual decrease.
    double alpha = 1.0;
    bool accepted = false;
    while (alpha > kMinStep) {
      xtry_ = (xcur_ + alpha * dx_).cwiseMax(lb).cwiseMin(ub);
      const double v = objective(H, g, xtry_);
      if (v - value <= kArmijo * grad_.dot(xtry_ - xcur_)) {
        accepted = true;
        xcur_.swap(xtry_);
        value = v;
        break;
      }
      alpha *= 0.5;
    }
    if (!accepted) {
      objective(H, g, xcur_);  // restore Hx_ for the final gradient
      break;
    }
  }
  // The free set at the solution, and its factor for the gains.
  grad_ = g + Hx_;
  nfree_ = 0;
  for (int i = 0; i < n_; ++i) {
    const bool clamped =
        (xcur_[i] <= lb[i] && grad_[i] > 0.0) || (xcur_[i] >= ub[i] && grad_[i] < 0.0);
    if (!clamped) free_[nfree_++] = i;
  }
  x = xcur_;
  return factorFree(H);
}

}  // namespace stride
