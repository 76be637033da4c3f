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
  computeRNEADerivatives(model, data, q, v, data.ddq);
  crba(model, data, q);
  factorizeMassMatrix(model, data);
  computeMinverse(model, data);
  data.ddq_dq.noalias() = -data.Minv * data.dtau_dq;
  data.ddq_dv.noalias() = -data.Minv * data.dtau_dv;
}

}  // namespace stride
