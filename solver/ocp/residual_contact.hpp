#pragma once
// Residuals on the contact forces λ = g(x, u) of the knot (KnotContext::forces, Gx, Gu): tracking
// a force, and keeping it inside a linearized friction cone. A contact is named at construction
// and looked up in the knot's ContactSet at every call, so the same term works on knots of every
// phase: where its contact is off (or the knot has no contacts) the residual and its Jacobians
// are zero, and so is its cost.

#include <string>

#include "solver/ocp/activation.hpp"
#include "solver/ocp/residual.hpp"

namespace stride {

// Offset of a contact's rows in the stacked λ of the active contacts (set order); -1 when the
// contact is inactive or out of range.
int forceOffset(const ContactSet& contacts, int contact);

// Base of the force residuals: the contact's name and dimension.
class ContactResidual : public Residual {
 public:
  const std::string& contact() const { return contact_; }
  int contactDim() const { return contact_dim_; }

 protected:
  // Throws std::invalid_argument when `contacts` has no contact of that name.
  ContactResidual(const Model& model, int nu, const ContactSet& contacts,
                  const std::string& contact, int dim, const char* who);
  // Offset of the contact's forces in ctx.forces, -1 when it is off at this knot. Throws
  // std::invalid_argument (a set-up error, never on a consistent problem) when the knot's contact
  // of that name has another dimension than the one the residual was built for.
  int offset(const KnotContext& ctx) const;

  // Residuals that are fixed rows A on the leading C entries of the contact's force (the friction
  // cone on f, the centre of pressure on [f; τ]): r = A λ_c, Rx = A Gx_c, Ru = A Gu_c, all zero
  // where the contact is off. linearRows returns false (r zeroed) when it is off.
  template <int R, int C>
  bool linearRows(ResidualData& d, const KnotContext& ctx,
                  const Eigen::Matrix<double, R, C>& A) const {
    const int off = offset(ctx);
    if (off < 0) {
      d.r.setZero();
      return false;
    }
    d.r.noalias() = A * ctx.forces->template segment<C>(off);
    return true;
  }
  template <int R, int C>
  void linearRowsDiff(ResidualData& d, const KnotContext& ctx,
                      const Eigen::Matrix<double, R, C>& A) const {
    const int off = offset(ctx);
    if (off < 0 || !ctx.Gx || !ctx.Gu) {
      d.Rx.setZero();
      d.Ru.setZero();
      return;
    }
    d.Rx.noalias() = A * ctx.Gx->template middleRows<C>(off);
    d.Ru.noalias() = A * ctx.Gu->template middleRows<C>(off);
  }

 private:
  std::string contact_;
  int contact_dim_;
};

// r = λ_c - λ_ref (dim 3 or 6, in the contact's force frame: LOCAL or LOCAL_WORLD_ALIGNED as the
// contact reports it), Rx = the contact's rows of Gx, Ru = those of Gu. Zero when the contact is
// off.
class ContactForceResidual : public ContactResidual {
 public:
  // Reference: zero when `reference` is empty; otherwise it must have the contact's dimension.
  ContactForceResidual(const Model& model, int nu, const ContactSet& contacts,
                       const std::string& contact,
                       const Eigen::VectorXd& reference = Eigen::VectorXd());
  // Throws std::invalid_argument for a size other than the contact's dimension.
  void setReference(const Eigen::Ref<const Eigen::VectorXd>& reference);
  const Eigen::VectorXd& reference() const { return reference_; }

  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  Eigen::VectorXd reference_;
};

// Linearized friction cone of a contact force f (the linear part for a 6D contact), as five rows
// that must all be ≤ 0. With f_s = R_surfaceᵀ f in the surface frame (z: the normal) and
// μ' = μ / √2 (the pyramid inscribed in the circular cone |f_t| ≤ μ f_n, so every force it
// accepts is truly inside the cone):
//   r = [ f_x - μ' f_z;  -f_x - μ' f_z;  f_y - μ' f_z;  -f_y - μ' f_z;  f_min - f_z ]
// Use activation() (upper bound 0). R_surface is expressed in the contact's force frame: the
// identity for LOCAL_WORLD_ALIGNED forces on flat ground. Zero when the contact is off.
class FrictionConeResidual : public ContactResidual {
 public:
  // Throws std::invalid_argument for an unknown contact, μ ≤ 0, a non-finite or negative minimum
  // normal force, or an R_surface that is not a rotation.
  FrictionConeResidual(const Model& model, int nu, const ContactSet& contacts,
                       const std::string& contact, double mu,
                       const Eigen::Matrix3d& R_surface = Eigen::Matrix3d::Identity(),
                       double min_normal_force = 0.0);

  // The bounds activation matching the rows: each row ≤ 0.
  static Activation activation(double weight = 1.0);

  // In place, no allocation; the same checks as the constructor.
  void setFriction(double mu);
  void setSurfaceRotation(const Eigen::Matrix3d& R_surface);
  void setMinimumNormalForce(double min_normal_force);
  double friction() const { return mu_; }
  const Eigen::Matrix3d& surfaceRotation() const { return R_surface_; }
  double minimumNormalForce() const { return min_force_; }
  // The rows' matrix A (r = A f + [0; 0; 0; 0; f_min]), in the contact's force frame.
  const Eigen::Matrix<double, 5, 3>& rows() const { return A_; }

  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  void updateRows();
  double mu_;
  Eigen::Matrix3d R_surface_;
  double min_force_;
  Eigen::Matrix<double, 5, 3> A_;
};

}  // namespace stride
