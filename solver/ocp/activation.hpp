#pragma once
// Activations turn a residual r into a scalar cost a(r). All of ours are sums over components,
// a(r) = Σ_i w_i φ(r_i), so the Hessian is diagonal and stored as a vector; weights, bounds and
// the smoothing constant can be rewritten every tick (sizes never change after setup).

#include <Eigen/Core>

namespace stride {

enum class ActivationKind : std::uint8_t {
  Quadratic,  // φ = ½ r²
  Bounds,     // quadratic barrier: φ = ½ (r - ub)² above ub, ½ (r - lb)² below lb, 0 between
  SmoothAbs,  // φ = sqrt(r² + ε²) - ε: quadratic near 0, linear (robust) far from it
};

struct Activation {
  ActivationKind kind = ActivationKind::Quadratic;
  Eigen::VectorXd weights;       // w_i ≥ 0
  Eigen::VectorXd lower, upper;  // Bounds only (may be ±infinity)
  double eps = 1e-2;             // SmoothAbs only

  static Activation quadratic(int dim, double weight = 1.0);
  static Activation weightedQuadratic(const Eigen::VectorXd& weights);
  // Throws std::invalid_argument unless lower ≤ upper componentwise and sizes agree.
  static Activation bounds(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                           double weight = 1.0);
  static Activation smoothAbs(int dim, double eps, double weight = 1.0);

  int dim() const { return static_cast<int>(weights.size()); }
  // a(r).
  double value(const Eigen::Ref<const Eigen::VectorXd>& r) const;
  // a(r), its gradient and its (diagonal) Hessian with respect to r.
  double derivatives(const Eigen::Ref<const Eigen::VectorXd>& r, Eigen::Ref<Eigen::VectorXd> Ar,
                     Eigen::Ref<Eigen::VectorXd> Arr) const;
};

}  // namespace stride
