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
                        const Eigen::Ref<const Eigen::VectorXd>& g,
                        const Eigen::Ref<const Eigen::VectorXd>& x) {
  const int n = static_cast<int>(H.rows());
  Hx_.head(n).noalias() = H * x;
  return 0.5 * x.dot(Hx_.head(n)) + g.dot(x);
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
  // The problem's size may be below the workspace's (knots with fewer controls): views of n.
  const int n = static_cast<int>(H.rows());
  auto xcur = xcur_.head(n), xtry = xtry_.head(n), grad = grad_.head(n), dx = dx_.head(n);
  const auto Hx = Hx_.head(n);
  iterations_ = 0;
  // Fast path: H is positive definite, so when the unconstrained minimizer -H^-1 g lies in the box
  // it is the solution, with every variable free. Most knots of a receding-horizon solve are
  // there (the torque limits bind on a few), and this costs one factorization, which the gains
  // reuse, instead of the loop's two and its line-search evaluations.
  nfree_ = n;
  for (int i = 0; i < n; ++i) free_[i] = i;
  if (factorFree(H)) {
    for (int i = 0; i < n; ++i) dx[i] = -g[i];
    auto step = dx;
    solveFree(step);
    if ((step.array() >= lb.array()).all() && (step.array() <= ub.array()).all()) {
      x = step;
      return true;
    }
  }
  xcur = x.cwiseMax(lb).cwiseMin(ub);
  double value = objective(H, g, xcur);
  auto freeSet = [&] {
    // A variable is clamped when it sits on a bound and the gradient pushes it outwards.
    nfree_ = 0;
    for (int i = 0; i < n; ++i) {
      const bool clamped =
          (xcur[i] <= lb[i] && grad[i] > 0.0) || (xcur[i] >= ub[i] && grad[i] < 0.0);
      if (!clamped) free_[nfree_++] = i;
    }
  };
  for (; iterations_ < kMaxIterations; ++iterations_) {
    grad = g + Hx;  // Hx holds H xcur from the last objective()
    freeSet();
    if (nfree_ == 0) break;
    double gnorm = 0.0;
    for (int a = 0; a < nfree_; ++a) gnorm = std::max(gnorm, std::abs(grad[free_[a]]));
    if (gnorm < kGradientTolerance) break;
    if (!factorFree(H)) return false;
    // Newton step on the free set, zero on the clamped one.
    auto step_f = rhs_.head(nfree_);
    for (int a = 0; a < nfree_; ++a) step_f[a] = -grad[free_[a]];
    solveFree(step_f);
    dx.setZero();
    for (int a = 0; a < nfree_; ++a) dx[free_[a]] = step_f[a];
    // Projected backtracking: the projection may bend the step, so test the actual decrease.
    double alpha = 1.0;
    bool accepted = false;
    while (alpha > kMinStep) {
      xtry = (xcur + alpha * dx).cwiseMax(lb).cwiseMin(ub);
      const double v = objective(H, g, xtry);
      if (v - value <= kArmijo * grad.dot(xtry - xcur)) {
        accepted = true;
        xcur = xtry;
        value = v;
        break;
      }
      alpha *= 0.5;
    }
    if (!accepted) {
      objective(H, g, xcur);  // restore Hx for the final gradient
      break;
    }
  }
  // The free set at the solution, and its factor for the gains.
  grad = g + Hx;
  freeSet();
  x = xcur;
  return factorFree(H);
}

}  // namespace stride
