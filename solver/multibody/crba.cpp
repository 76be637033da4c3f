#include "solver/multibody/crba.hpp"

#include "solver/multibody/joint.hpp"

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
  const int n = model.njoints();
  // Forward: placements, world motion subspaces and world body inertias in one sweep.
  for (int i = 1; i < n; ++i) {
    const Joint& j = model.joints[i];
    jointPlacement(j, q.data() + j.idx_q, data.liMi[i]);
    data.oMi[i] = data.oMi[j.parent] * data.liMi[i];
    const SE3& oMi = data.oMi[i];
    if (j.type == JointType::FreeFlyer)
      data.J.middleCols<6>(j.idx_v) = oMi.toActionMatrix();
    else
      data.J.col(j.idx_v) = jointSubspaceWorld(j, oMi);
    data.oYcrb[i] = model.inertias[i].transformedBy(oMi);
  }
  // Backward: F_k = Y_i S_k, the momentum of dof k's subtree moving at unit rate, with the
  // composite inertia Y_i of joint i's subtree; then M(k, r) = S_r . F_k for every dof k in the
  // subtree of r. The subtree is a contiguous range of columns (depth-first order), so column r of
  // the lower triangle is filled by a plain loop over memory in order.
  Eigen::MatrixXd& M = data.M;
  Matrix6Xd& F = data.Ag;  // scratch; the centroidal map is this matrix with moments at the CoM
  for (int i = n - 1; i > 0; --i) {
    const Joint& j = model.joints[i];
    data.oYcrb[i].mulColumns(data.J.middleCols(j.idx_v, j.nv), F.middleCols(j.idx_v, j.nv));
    for (int r = j.idx_v; r < j.idx_v + j.nv; ++r) {
      const Vector6d S = data.J.col(r);
      const int end = r + model.nvSubtree[r];
      for (int k = r; k < end; ++k) M(k, r) = S.dot(F.col(k));
    }
    if (j.parent > 0) data.oYcrb[j.parent] += data.oYcrb[i];
  }
  M.triangularView<Eigen::StrictlyUpper>() = M.transpose();
  return M;
}

}  // namespace stride
