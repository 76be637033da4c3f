#pragma once
// Articulated-Body Algorithm: forward dynamics v̇ = M(q)^-1 (tau - b(q, v)) in O(n)
// (Featherstone, RBDA §7.3). All sweeps are written in the world frame: articulated inertias
// computed for a child are then added to the parent's without a 6x6 change of frame, which is the
// costly step of the joint-frame version.

#include "solver/multibody/data.hpp"

namespace stride {

// v̇(q, v, tau) with no external force, written to data.ddq and returned.
const Eigen::VectorXd& aba(const Model& model, Data& data,
                           const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& v,
                           const Eigen::Ref<const Eigen::VectorXd>& tau);

}  // namespace stride
