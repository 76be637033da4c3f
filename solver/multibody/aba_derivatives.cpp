#include "solver/multibody/aba_derivatives.hpp"

#include "solver/multibody/aba.hpp"
#include "solver/multibody/cholesky.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/rnea_derivatives.hpp"

namespace stride {

void computeABADerivatives(const Model& model, Data& data,
                           const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& v,
                           const Eigen::Ref<const Eigen::VectorXd>& tau) {
  aba(model, data, q, v, tau);
  // crba first: the derivative sweep then reads its placements, subspaces and body inertias.
  crba(model, data, q);
  computeRNEADerivativesFromKinematics(model, data, v, data.ddq);
  factorizeMassMatrix(model, data);
  // One solve on the stacked right-hand sides [-∂τ/∂q, -∂τ/∂v, I].
  const int nv = model.nv;
  data.rhs3.leftCols(nv) = -data.dtau_dq;
  data.rhs3.middleCols(nv, nv) = -data.dtau_dv;
  data.rhs3.rightCols(nv).setIdentity();
  solveMassMatrixRows(model, data, data.rhs3);
  data.ddq_dq = data.rhs3.leftCols(nv);
  data.ddq_dv = data.rhs3.middleCols(nv, nv);
  data.Minv = data.rhs3.rightCols(nv);
}

}  // namespace stride
