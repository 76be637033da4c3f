#pragma once
// The centre of pressure of a surface (6D) contact inside its sole: a rigid sole can only push, so
// the ground's wrench [f; τ] at the sole's origin must have its centre of pressure
// p = (−τ_y, τ_x) / f_z inside the sole's rectangle |p_x| ≤ hx, |p_y| ≤ hy. A 6D contact alone
// would let the solver plan ankle torques that tip the foot over its edge; a real (or simulated)
// foot then rolls. Multiplied by f_z > 0 (the friction cone's last row keeps it positive), the
// rectangle is four linear rows that must all be ≤ 0:
//   r = [ τ_x − hy f_z;  −τ_x − hy f_z;  τ_y − hx f_z;  −τ_y − hx f_z ]
// in the sole's surface frame; R_surface is the sole's orientation in the contact's force frame
// (for LOCAL_WORLD_ALIGNED forces: the sole's world orientation, which the locomotion problem sets
// from each stance's planned heading, setSurface). Zero where the contact is off.

#include "solver/ocp/residual_contact.hpp"

namespace stride {

class CenterOfPressureResidual : public ContactResidual {
 public:
  // Throws std::invalid_argument for an unknown contact, a contact that is not 6D, half extents
  // that are not positive and finite, or an R_surface that is not a rotation.
  CenterOfPressureResidual(const Model& model, int nu, const ContactSet& contacts,
                           const std::string& contact, const Eigen::Vector2d& half_extents,
                           const Eigen::Matrix3d& R_surface = Eigen::Matrix3d::Identity());

  // The bounds activation matching the rows: each row ≤ 0.
  static Activation activation(double weight = 1.0);
  // A new sole orientation (no allocation; R_surface must be a rotation, unchecked here).
  void setSurface(const Eigen::Matrix3d& R_surface);
  // The rows' matrix A (r = A [f; τ]), in the contact's force frame.
  const Eigen::Matrix<double, 4, 6>& rows() const { return A_; }

  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  Eigen::Matrix<double, 4, 6> As_;  // on [f; τ] in the surface frame
  Eigen::Matrix<double, 4, 6> A_;
};

}  // namespace stride
