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
      data.J.col(j.idx_v) = oMi.act(jointSubspaceColumn(j, 0));
    // Kept per body as well: the RNEA derivatives from these kinematics reuse it.
    const Inertia Y = model.inertias[i].transformedBy(oMi);
    data.oYbody[i] = Y;
    data.oYcrb[i] = Y;
  }
  // Backward: M(r, k) = S_r . (Y_i S_k) for the dofs r supporting dof k; both triangles written
  // here, which is cheaper than a separate transpose pass over the whole matrix.
  Eigen::MatrixXd& M = data.M;
  for (int i = n - 1; i > 0; --i) {
    const Joint& j = model.joints[i];
    for (int k = j.idx_v; k < j.idx_v + j.nv; ++k) {
      const Vector6d F = data.oYcrb[i] * Vector6d(data.J.col(k));
      // F's entries as scalars in registers: a packet dot product would reload F from the stack
      // right after it was stored by halves, stalling on store forwarding at every row.
      const double f0 = F[0], f1 = F[1], f2 = F[2], f3 = F[3], f4 = F[4], f5 = F[5];
      for (int r = k; r >= 0; r = model.parentDof[r]) {
        const double* s = data.J.col(r).data();
        M(r, k) = s[0] * f0 + s[1] * f1 + s[2] * f2 + s[3] * f3 + s[4] * f4 + s[5] * f5;
      }
    }
    if (j.parent > 0) data.oYcrb[j.parent] += data.oYcrb[i];
  }
  M.triangularView<Eigen::StrictlyLower>() = M.transpose();
  return M;
}

}  // namespace stride
