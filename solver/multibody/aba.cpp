#include "solver/multibody/aba.hpp"

#include "solver/multibody/joint.hpp"

namespace stride {

const Eigen::VectorXd& aba(const Model& model, Data& data,
                           const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& v,
                           const Eigen::Ref<const Eigen::VectorXd>& tau) {
  model.checkConfiguration(q, "aba");
  model.checkVelocity(v, "aba");
  if (tau.size() != model.nv) throwSizeError("aba", "tau", model.nv, tau.size());
  const int n = model.njoints();

  // Pass 1 (root to leaves): placements, world motion subspaces S, velocities, the velocity-
  // product acceleration c = v x (S qd) and the bias force p = v x* (Y v).
  data.ov[0].setZero();
  for (int i = 1; i < n; ++i) {
    const Joint& j = model.joints[i];
    jointPlacement(j, q.data() + j.idx_q, data.liMi[i]);
    data.oMi[i] = data.oMi[j.parent] * data.liMi[i];
    const SE3& oMi = data.oMi[i];
    Vector6d vJ;  // S qd in the world frame
    if (j.type == JointType::FreeFlyer) {
      data.J.middleCols<6>(j.idx_v) = oMi.toActionMatrix();
      vJ = data.J.middleCols<6>(j.idx_v) * v.segment<6>(j.idx_v);
    } else {
      data.J.col(j.idx_v) = jointSubspaceWorld(j, oMi);
      vJ = data.J.col(j.idx_v) * v[j.idx_v];
    }
    data.ov[i] = data.ov[j.parent] + vJ;
    data.oc[i] = motionCross(data.ov[i], vJ);
    const Inertia oY = model.inertias[i].transformedBy(oMi);
    data.oYaba[i] = oY.matrix();
    data.of[i] = forceCross(data.ov[i], oY * data.ov[i]);
  }

  // Pass 2 (leaves to root): articulated inertias and bias forces.
  for (int i = n - 1; i > 0; --i) {
    const Joint& j = model.joints[i];
    const Matrix6d& Ia = data.oYaba[i];
    if (j.type == JointType::FreeFlyer) {
      // A free-flyer hangs from the fixed universe: its full-rank S leaves nothing to propagate.
      auto U = data.U.middleCols<6>(j.idx_v);
      U.noalias() = Ia * data.J.middleCols<6>(j.idx_v);
      data.rootLLT.compute(data.J.middleCols<6>(j.idx_v).transpose() * U);
      data.u.segment<6>(j.idx_v) =
          tau.segment<6>(j.idx_v) - data.J.middleCols<6>(j.idx_v).transpose() * data.of[i];
      continue;
    }
    const int k = j.idx_v;
    auto S = data.J.col(k);
    auto U = data.U.col(k);
    U.noalias() = Ia * S;
    const double Dinv = 1.0 / S.dot(U);
    data.Dinv[k] = Dinv;
    const double uk = tau[k] - S.dot(data.of[i]);
    data.u[k] = uk;
    if (j.parent == 0) continue;
    Matrix6d Ia_child = Ia;
    Ia_child.noalias() -= (Dinv * U) * U.transpose();
    data.oYaba[j.parent] += Ia_child;
    data.of[j.parent] += data.of[i] + Ia_child * data.oc[i] + (Dinv * uk) * U;
  }

  // Pass 3 (root to leaves): accelerations. The universe accelerates upward by -g.
  data.oa[0].head<3>() = -model.gravity;
  data.oa[0].tail<3>().setZero();
  for (int i = 1; i < n; ++i) {
    const Joint& j = model.joints[i];
    const Vector6d ap = data.oa[j.parent] + data.oc[i];
    if (j.type == JointType::FreeFlyer) {
      auto qdd = data.ddq.segment<6>(j.idx_v);
      qdd = data.rootLLT.solve(data.u.segment<6>(j.idx_v) -
                               data.U.middleCols<6>(j.idx_v).transpose() * ap);
      data.oa[i] = ap + data.J.middleCols<6>(j.idx_v) * qdd;
    } else {
      const int k = j.idx_v;
      const double qdd = data.Dinv[k] * (data.u[k] - data.U.col(k).dot(ap));
      data.ddq[k] = qdd;
      data.oa[i] = ap + data.J.col(k) * qdd;
    }
  }
  return data.ddq;
}

}  // namespace stride
