#include "solver/ocp/residual_cop.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace stride {

CenterOfPressureResidual::CenterOfPressureResidual(const Model& model, int nu,
                                                   const ContactSet& contacts,
                                                   const std::string& contact,
                                                   const Eigen::Vector2d& half_extents,
                                                   const Eigen::Matrix3d& R_surface)
    : ContactResidual(model, nu, contacts, contact, 4, "CenterOfPressureResidual") {
  if (contactDim() != 6)
    throw std::invalid_argument("CenterOfPressureResidual: contact '" + contact +
                                "' is not a surface (6D) contact");
  if (!half_extents.allFinite() || !(half_extents.minCoeff() > 0.0))
    throw std::invalid_argument("CenterOfPressureResidual: contact '" + contact +
                                "': the sole's half extents must be positive and finite");
  if (!R_surface.allFinite() ||
      !(R_surface.transpose() * R_surface).isApprox(Eigen::Matrix3d::Identity(), 1e-9) ||
      R_surface.determinant() < 0.0)
    throw std::invalid_argument("CenterOfPressureResidual: contact '" + contact +
                                "': the surface orientation is not a rotation");
  const double hx = half_extents.x(), hy = half_extents.y();
  As_ << 0, 0, -hy, 1, 0, 0,  //
      0, 0, -hy, -1, 0, 0,    //
      0, 0, -hx, 0, 1, 0,     //
      0, 0, -hx, 0, -1, 0;
  setSurface(R_surface);
}

void CenterOfPressureResidual::setSurface(const Eigen::Matrix3d& R_surface) {
  // The wrench in the surface frame is blockdiag(Rᵀ, Rᵀ) [f; τ] (same origin, rotated axes).
  A_.leftCols<3>().noalias() = As_.leftCols<3>() * R_surface.transpose();
  A_.rightCols<3>().noalias() = As_.rightCols<3>() * R_surface.transpose();
}

Activation CenterOfPressureResidual::activation(double weight) {
  return Activation::bounds(Eigen::VectorXd::Constant(4, -std::numeric_limits<double>::infinity()),
                            Eigen::VectorXd::Zero(4), weight);
}

void CenterOfPressureResidual::calc(ResidualData& d, const KnotContext& ctx,
                                    const Eigen::Ref<const Eigen::VectorXd>&,
                                    const Eigen::Ref<const Eigen::VectorXd>&) const {
  linearRows(d, ctx, A_);
}

void CenterOfPressureResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                        const Eigen::Ref<const Eigen::VectorXd>&,
                                        const Eigen::Ref<const Eigen::VectorXd>&) const {
  linearRowsDiff(d, ctx, A_);
}

}  // namespace stride
