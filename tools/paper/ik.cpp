#include "tools/paper/ik.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/data.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"

namespace stride {

double contactInverseDynamics(const Model& model, const StridePlan& plan, int k,
                              const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                              const Eigen::VectorXd& a, double force_damping, Eigen::VectorXd& tau,
                              std::array<Vector6d, 2>& force) {
  const int nv = model.nv, na = 6, nu = nv - na;
  Data data(model);
  const Eigen::VectorXd full = rnea(model, data, q, v, a);
  computeJointJacobians(model, data, q);
  updateFramePlacements(model, data);
  int nc = 0;
  for (int c = 0; c < 2; ++c) nc += plan.closed[k][c] ? 6 : 0;
  Eigen::MatrixXd Jc(nc, nv);
  int row = 0;
  for (int c = 0; c < 2; ++c) {
    if (!plan.closed[k][c]) continue;
    Matrix6Xd J = Matrix6Xd::Zero(6, nv);
    getFrameJacobian(model, data, model.getFrameId(plan.feet[c]), ReferenceFrame::LocalWorldAligned,
                     J);
    Jc.middleRows(row, 6) = J;
    row += 6;
  }
  force = {Vector6d::Zero(), Vector6d::Zero()};
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(nc);
  if (nc > 0) {
    const Eigen::MatrixXd A = Jc.leftCols(na).transpose();  // 6 x nc
    Eigen::MatrixXd AAt = A * A.transpose();
    AAt.diagonal().array() += force_damping * AAt.trace();
    lambda = A.transpose() * AAt.ldlt().solve(full.head(na));
  }
  row = 0;
  for (int c = 0; c < 2; ++c) {
    if (!plan.closed[k][c]) continue;
    force[c] = lambda.segment<6>(row);
    row += 6;
  }
  tau = full.tail(nu);
  if (nc > 0) tau -= Jc.rightCols(nu).transpose() * lambda;
  const Eigen::VectorXd base_res =
      full.head(na) -
      (nc > 0 ? Eigen::VectorXd(Jc.leftCols(na).transpose() * lambda) : Eigen::VectorXd::Zero(na));
  return base_res.norm();
}

IkTrajectory trackIk(const Model& model, const StridePlan& plan, const Eigen::VectorXd& q_nominal,
                     const IkOptions& o) {
  const int nq = model.nq, nv = model.nv, N = plan.N;
  const double dt = plan.options.dt;
  Data data(model);
  const std::array<int, 2> frames = {model.getFrameId(plan.feet[0]),
                                     model.getFrameId(plan.feet[1])};
  const int chest = model.getFrameId("chest");
  IkTrajectory out;
  out.q.assign(N + 1, q_nominal);
  Eigen::VectorXd q = q_nominal;
  Eigen::MatrixXd H(nv, nv);
  Eigen::VectorXd g(nv), dq(nv);
  Matrix6Xd J = Matrix6Xd::Zero(6, nv);
  for (int k = 0; k <= N; ++k) {
    // The first sample starts from the nominal posture; later ones from the previous solution.
    for (int it = 0; it < (k == 0 ? 10 : 1) * o.iterations; ++it) {
      computeJointJacobians(model, data, q);
      updateFramePlacements(model, data);
      H.setZero();
      g.setZero();
      // CoM.
      const Eigen::Matrix3Xd& Jcom = jacobianCenterOfMass(model, data, q);
      const Eigen::Vector3d e_com = plan.com[k] - data.com;
      H += o.w_com * Jcom.transpose() * Jcom;
      g += o.w_com * Jcom.transpose() * e_com;
      // Feet: the error in the foot's local frame, with the local Jacobian (first order).
      computeJointJacobians(model, data, q);
      updateFramePlacements(model, data);
      for (int c = 0; c < 2; ++c) {
        const SE3 target(Eigen::Matrix3d::Identity(), plan.foot[k][c]);
        const Vector6d e = log6(data.oMf[frames[c]].actInv(target));
        getFrameJacobian(model, data, frames[c], ReferenceFrame::Local, J);
        H += o.w_foot * J.transpose() * J;
        g += o.w_foot * J.transpose() * e;
      }
      // Base and chest upright (the free-flyer's local angular velocity is v[3:6]): without the
      // chest, the torso pitch is the cheapest way to move the CoM and the solution flips
      // between leaning back and forward.
      const Eigen::Vector3d e_base = log3(data.oMi[1].R.transpose());
      H.block<3, 3>(3, 3) += o.w_base * Eigen::Matrix3d::Identity();
      g.segment<3>(3) += o.w_base * e_base;
      getFrameJacobian(model, data, chest, ReferenceFrame::Local, J);
      const Eigen::Vector3d e_chest = log3(data.oMf[chest].R.transpose());
      H += o.w_base * J.bottomRows<3>().transpose() * J.bottomRows<3>();
      g += o.w_base * J.bottomRows<3>().transpose() * e_chest;
      // Posture.
      const Eigen::VectorXd e_post = difference(model, q, q_nominal);
      H.diagonal().tail(nv - 6).array() += o.w_posture;
      g.tail(nv - 6) += o.w_posture * e_post.tail(nv - 6);
      H.diagonal().array() += o.damping;
      // Joint limits, active set: a joint whose step would cross its limit is held there (a stiff
      // task dq_i = limit - q_i) and the step solved again.
      const int nj = nq - 7;
      const auto lower = model.lowerPositionLimit.tail(nj),
                 upper = model.upperPositionLimit.tail(nj);
      constexpr double kHold = 1e8;
      for (int pass = 0; pass < 4; ++pass) {
        dq = H.ldlt().solve(g);
        bool changed = false;
        for (int i = 0; i < nj; ++i) {
          const double qi = q[7 + i], next = qi + dq[6 + i];
          const double bound = next < lower[i] ? lower[i] : (next > upper[i] ? upper[i] : qi);
          if (bound == qi && next >= lower[i] && next <= upper[i]) continue;
          H(6 + i, 6 + i) += kHold;
          g[6 + i] += kHold * (bound - qi);
          changed = true;
        }
        if (!changed) break;
      }
      q = integrate(model, q, dq);
      q.tail(nj) = q.tail(nj).cwiseMax(lower).cwiseMin(upper);
      if (dq.norm() < o.tolerance) break;
    }
    out.q[k] = q;
    framesForwardKinematics(model, data, q);
    out.max_com_error =
        std::max(out.max_com_error, (centerOfMass(model, data, q) - plan.com[k]).norm());
    framesForwardKinematics(model, data, q);
    for (int c = 0; c < 2; ++c)
      out.max_foot_error =
          std::max(out.max_foot_error, (data.oMf[frames[c]].p - plan.foot[k][c]).norm());
  }
  out.v.assign(N + 1, Eigen::VectorXd::Zero(nv));
  out.a.assign(N + 1, Eigen::VectorXd::Zero(nv));
  for (int k = 1; k <= N; ++k) out.v[k] = difference(model, out.q[k - 1], out.q[k]) / dt;
  for (int k = 0; k < N; ++k) out.a[k] = (out.v[k + 1] - out.v[k]) / dt;
  out.tau.resize(N + 1);
  out.force.resize(N + 1);
  for (int k = 0; k <= N; ++k)
    out.max_base_residual = std::max(
        out.max_base_residual, contactInverseDynamics(model, plan, k, out.q[k], out.v[k], out.a[k],
                                                      o.force_damping, out.tau[k], out.force[k]));
  return out;
}

}  // namespace stride
