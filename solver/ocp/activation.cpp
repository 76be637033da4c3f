#include "solver/ocp/activation.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace stride {

Activation Activation::quadratic(int dim, double weight) {
  return weightedQuadratic(Eigen::VectorXd::Constant(dim, weight));
}

Activation Activation::weightedQuadratic(const Eigen::VectorXd& weights) {
  Activation a;
  a.kind = ActivationKind::Quadratic;
  a.weights = weights;
  return a;
}

Activation Activation::bounds(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                              double weight) {
  if (lower.size() != upper.size())
    throw std::invalid_argument("Activation::bounds: lower and upper differ in size");
  if ((lower.array() > upper.array()).any())
    throw std::invalid_argument("Activation::bounds: a lower bound exceeds its upper bound");
  Activation a;
  a.kind = ActivationKind::Bounds;
  a.weights = Eigen::VectorXd::Constant(lower.size(), weight);
  a.lower = lower;
  a.upper = upper;
  return a;
}

Activation Activation::smoothAbs(int dim, double eps, double weight) {
  if (!(eps > 0.0)) throw std::invalid_argument("Activation::smoothAbs: eps must be positive");
  Activation a;
  a.kind = ActivationKind::SmoothAbs;
  a.weights = Eigen::VectorXd::Constant(dim, weight);
  a.eps = eps;
  return a;
}

namespace {
// The violation of a bound: r - ub above, r - lb below, 0 inside.
inline double violation(double r, double lb, double ub) {
  if (std::isnan(r)) return r;  // a NaN residual must not read as "inside the bounds"
  if (r > ub) return r - ub;
  if (r < lb) return r - lb;
  return 0.0;
}
}  // namespace

double Activation::value(const Eigen::Ref<const Eigen::VectorXd>& r) const {
  double a = 0.0;
  const int n = dim();
  switch (kind) {
    case ActivationKind::Quadratic:
      for (int i = 0; i < n; ++i) a += 0.5 * weights[i] * r[i] * r[i];
      break;
    case ActivationKind::Bounds:
      for (int i = 0; i < n; ++i) {
        const double e = violation(r[i], lower[i], upper[i]);
        a += 0.5 * weights[i] * e * e;
      }
      break;
    case ActivationKind::SmoothAbs:
      for (int i = 0; i < n; ++i) a += weights[i] * (std::sqrt(r[i] * r[i] + eps * eps) - eps);
      break;
  }
  return a;
}

double Activation::derivatives(const Eigen::Ref<const Eigen::VectorXd>& r,
                               Eigen::Ref<Eigen::VectorXd> Ar,
                               Eigen::Ref<Eigen::VectorXd> Arr) const {
  double a = 0.0;
  const int n = dim();
  switch (kind) {
    case ActivationKind::Quadratic:
      for (int i = 0; i < n; ++i) {
        a += 0.5 * weights[i] * r[i] * r[i];
        Ar[i] = weights[i] * r[i];
        Arr[i] = weights[i];
      }
      break;
    case ActivationKind::Bounds:
      // The barrier's curvature is w outside the bounds and 0 inside (a kink at the bound that
      // Gauss-Newton handles as the active-set switch).
      for (int i = 0; i < n; ++i) {
        const double e = violation(r[i], lower[i], upper[i]);
        a += 0.5 * weights[i] * e * e;
        Ar[i] = weights[i] * e;
        Arr[i] = e != 0.0 ? weights[i] : 0.0;
      }
      break;
    case ActivationKind::SmoothAbs:
      for (int i = 0; i < n; ++i) {
        const double s = std::sqrt(r[i] * r[i] + eps * eps);
        a += weights[i] * (s - eps);
        Ar[i] = weights[i] * r[i] / s;
        Arr[i] = weights[i] * eps * eps / (s * s * s);
      }
      break;
  }
  return a;
}

}  // namespace stride
