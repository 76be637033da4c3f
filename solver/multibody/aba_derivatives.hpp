#pragma once
// Derivatives of forward dynamics v̇ = FD(q, v, τ). Differentiating M(q) v̇ + b(q, v) = τ at the
// solution gives ∂v̇/∂x = -M^-1 ∂τ_RNEA/∂x (x = q, v, evaluated at a = v̇) and ∂v̇/∂τ = M^-1:
// the RNEA derivatives, the CRBA and one tree-sparse factorization (Carpentier & Mansard 2018).

#include "solver/multibody/data.hpp"

namespace stride {

// Fills data.ddq (= aba), data.ddq_dq, data.ddq_dv and data.Minv (= ∂v̇/∂τ), all tangent-space.
void computeABADerivatives(const Model& model, Data& data,
                           const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& v,
                           const Eigen::Ref<const Eigen::VectorXd>& tau);

}  // namespace stride
