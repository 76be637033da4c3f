#include "solver/multibody/crba.hpp"

#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"

namespace stride {

void compositeInertiaSweep(const Model& model, Data& data, Matrix6Xd* F) {
  const int n = model.njoints();
  for (int i = 1; i < n; ++i) data.oYcrb[i] = model.inertias[i].transformedBy(data.oMi[i]);
  data.oYcrb[0] = Inertia::Zero();
  for (int i = n - 1; i > 0; --i) {
    const Joint& j = model.joints[i];
    if (F) data.oYcrb[i].mulColumns(data.J.middleCols(j.idx_v, j.nv), F->middleCols(j.idx_v, j.nv));
    data.oYcrb[j.parent] += data.oYcrb[i];
  }
}

const Eigen::MatrixXd& crba(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q) {
  model.checkConfiguration(q, "crba");
  forwardKinematics(model, data, q);
  updateJointJacobians(model, data);
  const int n = model.njoints();
  for (int i = 1; i < n; ++i) data.oYcrb[i] = model.inertias[i].transformedBy(data.oMi[i]);
  Eigen::MatrixXd& M = data.M;
  for (int i = n - 1; i > 0; --i) {
    const Joint& j = model.joints[i];
    for (int k = j.idx_v; k < j.idx_v + j.nv; ++k) {
      const Vector6d F = data.oYcrb[i] * Vector6d(data.J.col(k));
      // Upper triangle: rows are the supporting dofs r <= k.
      for (int r = k; r >= 0; r = model.parentDof[r]) M(r, k) = data.J.col(r).dot(F);
    }
    if (j.parent > 0) data.oYcrb[j.parent] += data.oYcrb[i];
  }
  M.triangularView<Eigen::StrictlyLower>() = M.transpose();
  return M;
}

}  // namespace stride
