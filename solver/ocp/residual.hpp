#pragma once
// Residuals r(x, u, λ) with analytical Jacobians in the tangent space (x = [q; v], dx = [dq; dv]).
// A residual that depends on the contact forces λ = g(x, u) gets its Jacobians by the chain rule
// through Gx, Gu (the Gauss-Newton terms of the paper's eq. 12): Rx = ∂r/∂λ Gx, Ru = ∂r/∂λ Gu.
//
// A cost term is residual × activation × weight (cost.hpp). Residual models hold their references
// (targets); setters rewrite them in place, without allocation, so the controller can move
// targets every tick.

#include <memory>

#include "solver/contact/contact_set.hpp"
#include "solver/multibody/data.hpp"

namespace stride {

// What a residual may read at a knot, valid when the knot calls the residual's calc / calcDiff:
//   data: forward kinematics of (q, v): data.oMi, data.v (joint velocities, local), data.J (joint
//         Jacobians, world). A residual may run further multibody algorithms on data at the same
//         q (e.g. the centre of mass) but must leave those fields consistent.
//   forces: the knot's contact forces λ (top nc entries, the active contacts stacked in the
//         set's order, each in its force frame), with Gx = ∂λ/∂x (nc x 2nv) and Gu = ∂λ/∂u
//         (nc x nu) after calcDiff. Null on knots without contacts (terminal knots).
struct KnotContext {
  const Model& model;
  Data& data;
  const ContactSet* contacts = nullptr;
  const Eigen::VectorXd* forces = nullptr;
  const Eigen::MatrixXd* Gx = nullptr;
  const Eigen::MatrixXd* Gu = nullptr;
};

// Per-residual workspace, built once by its residual.
struct ResidualData {
  ResidualData(int dim, int ndx, int nu);
  virtual ~ResidualData() = default;
  Eigen::VectorXd r;   // dim
  Eigen::MatrixXd Rx;  // dim x ndx
  Eigen::MatrixXd Ru;  // dim x nu
  Matrix6Xd J6;        // 6 x nv workspace (a frame Jacobian)
};

// Which columns of Rx / Ru can be nonzero: the cost's Gauss-Newton products skip the rest.
enum class Dependence : std::uint8_t {
  Configuration,  // q only: Rx has nonzero columns only in its first nv
  State,          // q and v
  Control,        // u only
  StateControl,   // x and u (e.g. through the contact forces)
};

// Views of the cost derivatives a knot accumulates (ℓ = Σ weight · a(r)) - they live in the
// knot's data - and of a workspace for the products (max residual dim rows).
struct CostDerivatives {
  Eigen::Ref<Eigen::VectorXd> Lx, Lu;
  Eigen::Ref<Eigen::MatrixXd> Lxx, Lxu, Luu;
  Eigen::Ref<Eigen::MatrixXd> HRx, HRu;  // diag(h) Rx, diag(h) Ru
};

class Residual {
 public:
  Residual(int dim, int nv, int nu, Dependence dependence)
      : dim_(dim), nv_(nv), nu_(nu), dependence_(dependence) {}
  virtual ~Residual() = default;
  Residual(const Residual&) = delete;
  Residual& operator=(const Residual&) = delete;

  int dim() const { return dim_; }
  int nv() const { return nv_; }
  int nu() const { return nu_; }
  Dependence dependence() const { return dependence_; }

  // The data may depend on the residual's type and sizes only, not on its parameters or
  // references, and calcDiff must rewrite every entry that addGaussNewton reads (constant entries
  // set here, e.g. an identity, stay valid): the knots of a problem share one cost workspace per
  // thread between residuals of the same type and dimension (knot.hpp, SharedWorkspace).
  virtual std::unique_ptr<ResidualData> createData() const {
    return std::make_unique<ResidualData>(dim_, 2 * nv_, nu_);
  }
  // r (d.r).
  virtual void calc(ResidualData& d, const KnotContext& ctx,
                    const Eigen::Ref<const Eigen::VectorXd>& x,
                    const Eigen::Ref<const Eigen::VectorXd>& u) const = 0;
  // Rx, Ru (d.Rx, d.Ru), after calc at the same (x, u). Entries outside the columns named by
  // dependence() are never read.
  virtual void calcDiff(ResidualData& d, const KnotContext& ctx,
                        const Eigen::Ref<const Eigen::VectorXd>& x,
                        const Eigen::Ref<const Eigen::VectorXd>& u) const = 0;
  // Adds the Gauss-Newton terms of weight · a(r): L += Rᵀ g and L.. += Rᵀ diag(h) R, with g, h the
  // weighted gradient and diagonal Hessian of the activation. The default forms the products over
  // the columns named by dependence(); a residual with a sparser Jacobian overrides it (the state
  // residual's is the identity except a 6 x 6 block).
  virtual void addGaussNewton(const ResidualData& d, const Eigen::Ref<const Eigen::VectorXd>& g,
                              const Eigen::Ref<const Eigen::VectorXd>& h,
                              CostDerivatives& out) const;

 private:
  int dim_, nv_, nu_;
  Dependence dependence_;
};

}  // namespace stride
