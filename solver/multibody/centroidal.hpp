#pragma once
// Centroidal momentum h_g = [m c_dot; angular momentum about the CoM] in world-aligned axes,
// and the centroidal momentum matrix A_g (Orin, Goswami & Lee 2013), h_g = A_g(q) v.

#include "solver/multibody/data.hpp"

namespace stride {

// h_g (data.hg), with data.com and data.vcom. Runs forward kinematics with v.
const Vector6d& computeCentroidalMomentum(const Model& model, Data& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& q,
                                          const Eigen::Ref<const Eigen::VectorXd>& v);
// A_g (data.Ag, 6 x nv) and data.com, from the composite-inertia sweep of the CRBA.
const Matrix6Xd& computeCentroidalMap(const Model& model, Data& data,
                                      const Eigen::Ref<const Eigen::VectorXd>& q);

}  // namespace stride
