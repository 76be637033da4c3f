#pragma once
// Composite Rigid Body Algorithm: the joint-space inertia matrix M(q) (Featherstone, RBDA §6.2).
// Written in the world frame: with every motion subspace S_k and composite inertia Y_i in world
// coordinates, M(j, k) = S_j^T (Y_i S_k) for every dof j supporting dof k of joint i; no spatial
// transforms are needed inside the double loop.

#include "solver/multibody/data.hpp"

namespace stride {

// M(q), full symmetric, written to data.M and returned. Also fills data.oMi, data.J, data.oYcrb.
const Eigen::MatrixXd& crba(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q);

// The backward composite-inertia sweep shared with the centroidal algorithms: from data.oMi and
// data.J, fills data.oYcrb (world-frame subtree inertias); when F is given, F.col(k) is the
// world-frame momentum Y_i S_k of dof k's subtree moving with unit rate.
void compositeInertiaSweep(const Model& model, Data& data, Matrix6Xd* F);

}  // namespace stride
