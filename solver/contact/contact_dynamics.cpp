#include "solver/contact/contact_dynamics.hpp"

#include <algorithm>

#include "solver/multibody/cholesky.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/frame_derivatives.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/rnea_derivatives.hpp"

namespace stride {

const char* toString(ContactStatus status) {
  switch (status) {
    case ContactStatus::Ok:
      return "ok";
    case ContactStatus::NonFinite:
      return "non-finite input";
    case ContactStatus::Singular:
      return "singular contact Jacobian (add damping)";
    case ContactStatus::SingularMassMatrix:
      return "singular mass matrix (a moving body without inertia?)";
  }
  return "?";
}

ContactData::ContactData(const Model& model, const ContactSet& contacts) {
  const int nv = model.nv, m = contacts.maxNc();
  Jc = Eigen::MatrixXd::Zero(m, nv);
  gamma = lambda = impulses = rhs = Eigen::VectorXd::Zero(m);
  ddq = v_after = zero = Eigen::VectorXd::Zero(nv);
  ddq_dq = ddq_dv = ddq_dtau = Eigen::MatrixXd::Zero(nv, nv);
  lambda_dq = lambda_dv = lambda_dtau = Yt = dacc_dq = dacc_dv = Eigen::MatrixXd::Zero(m, nv);
  rhs3 = RowMatrixXd::Zero(nv, 3 * nv);
  work = Eigen::MatrixXd::Zero(m, 3 * nv);
  Kinv = Eigen::MatrixXd::Zero(m, m);
  dual_rows = RowMatrixXd::Zero(m, 3 * nv);
  K = Eigen::MatrixXd::Zero(m, m);
  Jframe = dv_dq = dv_dv = da_dq = da_dv = Matrix6Xd::Zero(6, nv);
  rows3 = Eigen::Matrix3Xd::Zero(3, nv);
  fext.assign(static_cast<size_t>(model.njoints()), Vector6d::Zero());
}

namespace {

bool finite(const Eigen::Ref<const Eigen::VectorXd>& x) {
  return x.allFinite();
}

void clearOutputs(ContactData& cd) {
  cd.ddq.setZero();
  cd.v_after.setZero();
  cd.lambda.setZero();
  cd.impulses.setZero();
}

SE3 framePlacement(const Model& model, const Data& data, int frame) {
  const Frame& f = model.frames[frame];
  return data.oMi[f.parentJoint] * f.placement;
}

// Jc (LOCAL rows) from data.J; with kinematics of (q, v, a = 0) in data.v, data.a, also the drift
// γ. Needs crba (or computeJointJacobians) first.
void constraintRows(const Model& model, Data& data, const ContactSet& contacts, ContactData& cd,
                    bool with_drift) {
  int r = 0;
  for (int c = 0; c < contacts.size(); ++c) {
    if (!contacts.isActive(c)) continue;
    const ContactModel& cm = contacts[c];
    // The LOCAL frame Jacobian's rows, written straight into Jc and only on the supporting
    // columns: X_f^-1 S = [R^T (S_lin - p x S_ang); R^T S_ang].
    const SE3 oMf = framePlacement(model, data, cm.frame);
    const Eigen::Matrix3d Rt = oMf.R.transpose();
    auto rows = cd.Jc.middleRows(r, cm.dim);
    rows.setZero();
    const Joint& jt = model.joints[model.frames[cm.frame].parentJoint];
    for (int k = jt.idx_v + jt.nv - 1; k >= 0; k = model.parentDof[k]) {
      const Eigen::Vector3d S_lin = data.J.col(k).head<3>(), S_ang = data.J.col(k).tail<3>();
      rows.col(k).head<3>().noalias() = Rt * (S_lin - oMf.p.cross(S_ang));
      if (cm.dim == 6) rows.col(k).tail<3>().noalias() = Rt * S_ang;
    }
    if (with_drift) {
      // The frame's LOCAL velocity and acceleration from its joint's (joint frame), in 3-vector
      // halves: X^-1 m = [R^T (m_l - p x m_a); R^T m_a] with the frame's placement in its joint.
      const SE3& X = model.frames[cm.frame].placement;
      const Vector6d& vi = data.v[model.frames[cm.frame].parentJoint];
      const Vector6d& ai = data.a[model.frames[cm.frame].parentJoint];
      const Eigen::Vector3d v_a = X.R.transpose() * vi.tail<3>();
      const Eigen::Vector3d v_l = X.R.transpose() * (vi.head<3>() - X.p.cross(vi.tail<3>()));
      const Eigen::Vector3d a_l = X.R.transpose() * (ai.head<3>() - X.p.cross(ai.tail<3>()));
      if (cm.dim == 3) {
        Eigen::Vector3d g = a_l + v_a.cross(v_l) + cm.kd * v_l;
        if (cm.kp > 0) g += cm.kp * (Rt * (oMf.p - cm.reference.p));
        cd.gamma.segment<3>(r) = g;
      } else {
        const Eigen::Vector3d a_a = X.R.transpose() * ai.tail<3>();
        cd.gamma.segment<3>(r) = a_l + cm.kd * v_l;
        cd.gamma.segment<3>(r + 3) = a_a + cm.kd * v_a;
        if (cm.kp > 0) cd.gamma.segment<6>(r) += cm.kp * log6(cm.reference.actInv(oMf));
      }
    }
    r += cm.dim;
  }
  cd.nc = r;
}

// Yt = (M^-1 Jc^T)^T = Jc M^-1 and the Cholesky factor of K = Jc M^-1 Jc^T + μ I, in place in
// K's lower triangle. Yt is stored nc x nv so that the solve runs on rows of its transpose.
bool factorSchur(const Model& model, const Data& data, ContactData& cd, double damping) {
  const int nc = cd.nc;
  if (nc == 0) return true;
  auto Yt = cd.Yt.topRows(nc);
  Yt = cd.Jc.topRows(nc);
  solveMassMatrixRows(model, data, Yt.transpose());
  auto K = cd.K.topLeftCorner(nc, nc);
  K.noalias() = Yt * cd.Jc.topRows(nc).transpose();
  K.diagonal().array() += damping;
  // In-place LLT on the block: no allocation, and the factor stays in K for later solves. LLT only
  // fails on a non-positive pivot; a rank-deficient K usually leaves a tiny positive one instead,
  // with forces split arbitrarily between redundant contacts, so small pivots count as singular.
  // With damping μ every pivot is at least μ in exact arithmetic: that is the user's choice.
  const double threshold =
      damping > 0.0 ? 0.5 * damping : 1e-10 * std::max(1.0, K.diagonal().maxCoeff());
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(K);
  if (llt.info() != Eigen::Success) return false;
  return K.diagonal().cwiseAbs2().minCoeff() > threshold;  // K holds L now: L_ii^2 = pivot
}

// The workspace must have been built for this set and model (a set may not grow afterwards).
void checkWorkspace(const Model& model, const ContactSet& contacts, const ContactData& cd,
                    const char* fn) {
  if (cd.Jc.cols() != model.nv) throwSizeError(fn, "ContactData (nv)", model.nv, cd.Jc.cols());
  if (cd.Jc.rows() < contacts.maxNc())
    throwSizeError(fn, "ContactData (contact rows)", contacts.maxNc(), cd.Jc.rows());
}

// X <- K^-1 X with the factor in K's lower triangle.
template <typename Derived>
void solveSchur(const ContactData& cd, Eigen::MatrixBase<Derived>& X) {
  const auto L = cd.K.topLeftCorner(cd.nc, cd.nc).template triangularView<Eigen::Lower>();
  L.solveInPlace(X);
  L.adjoint().solveInPlace(X);
}

// Contact forces as reported (each in its contact's force frame) -> LOCAL values in cd.rhs (the
// rotation of LOCAL_WORLD_ALIGNED contacts undone) -> joint wrenches in cd.fext, for the RNEA
// derivatives.
void localForcesToJointWrenches(const Model& model, const Data& data, const ContactSet& contacts,
                                ContactData& cd, const Eigen::VectorXd& reported) {
  for (auto& f : cd.fext) f.setZero();
  int r = 0;
  for (int c = 0; c < contacts.size(); ++c) {
    if (!contacts.isActive(c)) continue;
    const ContactModel& cm = contacts[c];
    const Frame& fr = model.frames[cm.frame];
    cd.rhs.segment(r, cm.dim) = reported.segment(r, cm.dim);
    if (cm.forces == ReferenceFrame::LocalWorldAligned) {
      const SE3 oMf = framePlacement(model, data, cm.frame);
      for (int b = 0; b < cm.dim; b += 3)
        cd.rhs.segment<3>(r + b) = oMf.R.transpose() * cd.rhs.segment<3>(r + b);
    }
    Vector6d w = Vector6d::Zero();
    if (cm.dim == 3)
      w.head<3>() = cd.rhs.segment<3>(r);
    else
      w = cd.rhs.segment<6>(r);
    cd.fext[fr.parentJoint] += fr.placement.actForce(w);
    r += cm.dim;
  }
}

// Rotates LOCAL forces (and their derivatives) of LOCAL_WORLD_ALIGNED contacts to world axes.
// λ_w = R λ_l, so ∂λ_w = R ∂λ_l + (∂R) λ_l, and ∂R/∂q_j λ_l = ω_j x λ_w (ω_j: world angular
// Jacobian column of the frame).
// Only the columns [tau_first, nv) of dtau are touched.
void rotateForces(const Model& model, const Data& data, const ContactSet& contacts,
                  Eigen::VectorXd& forces, Eigen::MatrixXd* dq, Eigen::MatrixXd* dv,
                  Eigen::MatrixXd* dtau, int tau_first = 0) {
  int r = 0;
  for (int c = 0; c < contacts.size(); ++c) {
    if (!contacts.isActive(c)) continue;
    const ContactModel& cm = contacts[c];
    if (cm.forces == ReferenceFrame::LocalWorldAligned) {
      const SE3 oMf = framePlacement(model, data, cm.frame);
      const Joint& jt = model.joints[model.frames[cm.frame].parentJoint];
      for (int b = 0; b < cm.dim; b += 3) {
        auto f = forces.segment<3>(r + b);
        f = oMf.R * Eigen::Vector3d(f);
        // Column by column with fixed sizes: Eigen sends a 3 x 3 times 3 x nv product to its
        // blocked GEMM, whose packing costs more than the arithmetic.
        for (Eigen::MatrixXd* m : {dq, dv, dtau}) {
          if (!m) continue;
          for (Eigen::Index j = m == dtau ? tau_first : 0; j < m->cols(); ++j) {
            auto x = m->col(j).segment<3>(r + b);
            const Eigen::Vector3d y = x;
            x.noalias() = oMf.R * y;
          }
        }
        // (∂R) λ_l: minus f x ω_k on the supporting columns (ω_k: world angular Jacobian column,
        // the frame's LOCAL_WORLD_ALIGNED one).
        if (dq)
          for (int k = jt.idx_v + jt.nv - 1; k >= 0; k = model.parentDof[k]) {
            const Eigen::Vector3d w = data.J.col(k).tail<3>();
            dq->col(k).segment<3>(r + b) -= Eigen::Vector3d(f).cross(w);
          }
      }
    }
    r += cm.dim;
  }
}

// row += Σ_r jc[r] d_r for Dim rows d_r of length n (stride ld): the rows of Jc^T ∂λ/∂x a contact
// adds to, one pass over each output row with the Dim coefficients in registers.
template <int Dim>
void addTransposedRows(const double* jc, const double* d, Eigen::Index ld, double* __restrict row,
                       int n) {
  double c[Dim];
  for (int r = 0; r < Dim; ++r) c[r] = jc[r];
  for (int j = 0; j < n; ++j) {
    double acc = row[j];
    for (int r = 0; r < Dim; ++r) acc += c[r] * d[r * ld + j];
    row[j] = acc;
  }
}

// The common tail of both derivative computations. With R_x in data.dtau_dq (and dtau_dv) and
// the constraint derivatives A_x in cd.dacc_dq (and dacc_dv):
//   ∂λ/∂x = K^-1 (Yt R_x - A_x),   ∂λ/∂τ = -K^-1 Yt,
//   ∂v̇/∂x = M^-1 (-R_x + Jc^T ∂λ/∂x),   ∂v̇/∂τ = M^-1 (I + Jc^T ∂λ/∂τ),
// the second line from the first block row of the differentiated KKT system. The primal
// derivatives then share one solve with M on the stacked right-hand sides [q | v | τ], and M^-1
// itself is never formed. The τ block covers the columns [tau_first, nv) only (the knot needs
// the actuated ones).
//
// Jc^T ∂λ/∂x is written for Jc's sparsity (a contact's rows are zero outside the dofs supporting
// it) instead of as a dense GEMM: on talos_reduced a third of the arithmetic, and no packing.
// Yt R_x stays a dense GEMM: R_x has M's tree pattern too, but exploiting it needs one short
// update of nc entries per nonzero, and their loop overhead measured slower than the GEMM.
void kktDerivatives(const Model& model, Data& data, const ContactSet& contacts, ContactData& cd,
                    Eigen::MatrixXd& primal_dq, Eigen::MatrixXd& dual_dq,
                    Eigen::MatrixXd* primal_dv, Eigen::MatrixXd* dual_dv,
                    Eigen::MatrixXd* primal_dtau, Eigen::MatrixXd* dual_dtau, int tau_first,
                    bool primal_matrices = true) {
  const int nc = cd.nc, nv = model.nv;
  // K^-1 explicitly: it is at most a few dozen rows, and one small product is cheaper than a
  // triangular solve.
  inverseFromCholesky(cd.K, nc, cd.Kinv);  // from the factor in K's lower triangle
  const auto Kinv = cd.Kinv.topLeftCorner(nc, nc);
  // The requested blocks side by side, [q | v | τ columns tau_first..nv-1], in cd.work (for ∂λ)
  // and cd.rhs3 (for ∂v̇): ∂λ then takes one product with K^-1 and the Jc^T update one pass over
  // long rows, instead of one each per block (at these sizes, the calls and the packing of small
  // products cost as much as their arithmetic).
  struct Block {
    const Eigen::MatrixXd* R;  // null for τ
    const Eigen::MatrixXd* A;
    Eigen::MatrixXd* primal;
    Eigen::MatrixXd* dual;
    int cols = 0, offset = 0;
  } blocks[] = {{&data.dtau_dq, &cd.dacc_dq, &primal_dq, &dual_dq},
                {&data.dtau_dv, &cd.dacc_dv, primal_dv, dual_dv},
                {nullptr, nullptr, primal_dtau, dual_dtau}};
  int used = 0;
  for (Block& b : blocks) {
    if (!b.primal) continue;
    b.cols = b.R ? nv : nv - tau_first;
    b.offset = used;
    used += b.cols;
    auto rhs = cd.rhs3.middleCols(b.offset, b.cols);
    if (b.R) {
      if (nc > 0) {
        auto work = cd.work.block(0, b.offset, nc, b.cols);
        work.noalias() = cd.Yt.topRows(nc) * *b.R;
        work -= b.A->topRows(nc);
      }
      rhs = -*b.R;
    } else {
      if (nc > 0) cd.work.block(0, b.offset, nc, b.cols) = -cd.Yt.topRows(nc).rightCols(b.cols);
      rhs.setZero();
      rhs.bottomRows(b.cols).diagonal().setOnes();
    }
  }
  // No contact closed: v̇'s derivatives are ABA's, and there is no λ. Not only a shortcut: a set
  // without any contact has workspaces of no rows, whose data() is null, and a block of one at a
  // column offset is undefined behaviour (found by UndefinedBehaviorSanitizer).
  if (nc > 0) {
    // ∂λ/∂x, row-major for the row updates below, then to its outputs.
    auto dual = cd.dual_rows.topLeftCorner(nc, used);
    dual.noalias() = Kinv * cd.work.topLeftCorner(nc, used);
    for (const Block& b : blocks)
      if (b.primal) b.dual->topRows(nc).rightCols(b.cols) = dual.middleCols(b.offset, b.cols);
    // rhs += Jc^T dual on the supporting rows of each contact.
    const Eigen::Index stride = cd.rhs3.outerStride(), ldd = cd.dual_rows.outerStride();
    int r = 0;
    for (int c = 0; c < contacts.size(); ++c) {
      if (!contacts.isActive(c)) continue;
      const ContactModel& cm = contacts[c];
      const Joint& jt = model.joints[model.frames[cm.frame].parentJoint];
      const double* d = cd.dual_rows.data() + r * ldd;
      for (int k = jt.idx_v + jt.nv - 1; k >= 0; k = model.parentDof[k]) {
        double* row = cd.rhs3.data() + k * stride;
        if (cm.dim == 3)
          addTransposedRows<3>(&cd.Jc(r, k), d, ldd, row, used);
        else
          addTransposedRows<6>(&cd.Jc(r, k), d, ldd, row, used);
      }
      r += cm.dim;
    }
  }
  solveMassMatrixRows(model, data, cd.rhs3.leftCols(used));
  if (!primal_matrices) return;
  for (const Block& b : blocks)
    if (b.primal) b.primal->rightCols(b.cols) = cd.rhs3.middleCols(b.offset, b.cols);
}

// The factorizations both solves share: M (crba + tree-sparse L^T D L), the constraint rows and
// the Schur complement. With v, also b(q, v) in data.nle and the drift γ; the RNEA sweep of b
// holds the joint velocities and, at v̇ = 0, the accelerations with gravity a_gf = X^-1 a_0 + a,
// so removing the gravity term gives the drift's accelerations without another sweep.
ContactStatus factorKkt(const Model& model, Data& data, const ContactSet& contacts, ContactData& cd,
                        const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>* v, double damping) {
  crba(model, data, q);
  if (!factorizeMassMatrix(model, data)) {
    clearOutputs(cd);
    return ContactStatus::SingularMassMatrix;
  }
  if (v) {
    // crba(q) has just left q's placements in data.liMi and data.oMi.
    nonLinearEffectsFromKinematics(model, data, *v);
    // a = a_gf - X_i^-1 [-g; 0] = a_gf + [R_i^T g; 0], in 3-vector halves (no 6-vector temporary).
    for (int i = 1; i < model.njoints(); ++i) {
      data.a[i].head<3>() = data.a_gf[i].head<3>() + data.oMi[i].R.transpose() * model.gravity;
      data.a[i].tail<3>() = data.a_gf[i].tail<3>();
    }
  }
  constraintRows(model, data, contacts, cd, v != nullptr);
  if (!factorSchur(model, data, cd, damping)) {
    clearOutputs(cd);
    return ContactStatus::Singular;
  }
  return ContactStatus::Ok;
}

// A_x = ∂(constraint acceleration)/∂(q, v) of the active contacts into cd.dacc_dq, cd.dacc_dv, from
// the world sweep of computeRNEADerivatives. The frame acceleration derivatives of
// frame_derivatives.hpp, fused with the constraint's own terms and written only on the columns of
// the dofs supporting each contact: the generic getFrameAccelerationDerivatives fills and zeroes
// four 6 x nv blocks per contact, several times the arithmetic needed here. Per supporting dof k
// (world, spatial; S, w, e as in rnea_derivatives.cpp; i the frame's joint, λ the parent of k's
// joint):
//   ∂v/∂q_k = w,  ∂a/∂q_k = a_λ x S + w x (v_i - v_λ),  ∂v/∂v_k = S,  ∂a/∂v_k = S x v_i + e.
// A point contact's classical acceleration a_lin + ω x ν + kd ν (+ kp R^T (p - p_ref)) is
// differentiated at the frame origin p in world axes, with scalar 3-vector code, then rotated to
// LOCAL by R^T: cross products commute with the rotation. ν(m) = m_lin + m_ang x p is the
// velocity of a motion m at p.
void constraintDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                           ContactData& cd) {
  const int nc = cd.nc;
  cd.dacc_dq.topRows(nc).setZero();
  cd.dacc_dv.topRows(nc).setZero();
  const Eigen::Vector3d a0 = data.oa[0].head<3>();  // the sweep's gravity term, not a motion
  int r = 0;
  for (int c = 0; c < contacts.size(); ++c) {
    if (!contacts.isActive(c)) continue;
    const ContactModel& cm = contacts[c];
    const int i = model.frames[cm.frame].parentJoint;
    const SE3 oMf = framePlacement(model, data, cm.frame);
    const Eigen::Matrix3d Rt = oMf.R.transpose();
    const Eigen::Vector3d p = oMf.p;
    const Eigen::Vector3d vi_lin = data.ov[i].head<3>(), wi = data.ov[i].tail<3>();
    const Eigen::Vector3d nu_f = vi_lin + wi.cross(p);  // velocity of the frame origin
    const Eigen::Vector3d err = p - cm.reference.p;     // R e, e the LOCAL position error
    const double kd = cm.kd, kp = cm.kp;
    const bool surface_kp = cm.dim == 6 && kp > 0;
    if (surface_kp) cd.Jframe.setZero();
    for (int jj = i; jj > 0; jj = model.joints[jj].parent) {
      const Joint& joint = model.joints[jj];
      const Vector6d& vp = data.ov[joint.parent];
      const Eigen::Vector3d ap_lin = data.oa[joint.parent].head<3>() - a0;
      const Eigen::Vector3d ap_ang = data.oa[joint.parent].tail<3>();
      const Eigen::Vector3d dv_lin = vi_lin - vp.head<3>(), dv_ang = wi - vp.tail<3>();
      for (int k = joint.idx_v; k < joint.idx_v + joint.nv; ++k) {
        const Eigen::Vector3d S_lin = data.J.col(k).head<3>(), S_ang = data.J.col(k).tail<3>();
        const Eigen::Vector3d w_lin = data.dW.col(k).head<3>(), w_ang = data.dW.col(k).tail<3>();
        // ∂a/∂q_k = a_λ x S + w x (v_i - v_λ), ∂a/∂v_k = S x v_i + e (motion cross products).
        const Eigen::Vector3d aq_ang = ap_ang.cross(S_ang) + w_ang.cross(dv_ang);
        const Eigen::Vector3d aq_lin =
            ap_ang.cross(S_lin) + ap_lin.cross(S_ang) + w_ang.cross(dv_lin) + w_lin.cross(dv_ang);
        const Eigen::Vector3d av_ang = S_ang.cross(wi) + data.dE.col(k).tail<3>();
        const Eigen::Vector3d av_lin =
            S_ang.cross(vi_lin) + S_lin.cross(wi) + data.dE.col(k).head<3>();
        if (cm.dim == 3) {
          const Eigen::Vector3d w_p = w_lin + w_ang.cross(p), S_p = S_lin + S_ang.cross(p);
          Eigen::Vector3d gq =
              aq_lin + aq_ang.cross(p) + kd * w_p + wi.cross(w_p) - nu_f.cross(w_ang);
          const Eigen::Vector3d gv =
              av_lin + av_ang.cross(p) + kd * S_p + wi.cross(S_p) - nu_f.cross(S_ang);
          if (kp > 0) gq += kp * (S_p + err.cross(S_ang));
          cd.dacc_dq.col(k).segment<3>(r).noalias() = Rt * gq;
          cd.dacc_dv.col(k).segment<3>(r).noalias() = Rt * gv;
        } else {
          // LOCAL spatial: X_f^-1 m = [R^T (m_lin - p x m_ang); R^T m_ang].
          const Eigen::Vector3d q_ang = aq_ang + kd * w_ang, v_ang = av_ang + kd * S_ang;
          const Eigen::Vector3d q_lin = aq_lin + kd * w_lin - p.cross(q_ang);
          const Eigen::Vector3d v_lin = av_lin + kd * S_lin - p.cross(v_ang);
          auto dq = cd.dacc_dq.col(k).segment<6>(r);
          auto dv = cd.dacc_dv.col(k).segment<6>(r);
          dq.head<3>().noalias() = Rt * q_lin;
          dq.tail<3>().noalias() = Rt * q_ang;
          dv.head<3>().noalias() = Rt * v_lin;
          dv.tail<3>().noalias() = Rt * v_ang;
          if (surface_kp) {
            cd.Jframe.col(k).head<3>().noalias() = Rt * (S_lin - p.cross(S_ang));
            cd.Jframe.col(k).tail<3>().noalias() = Rt * S_ang;
          }
        }
      }
    }
    // α = a + kd v + kp log6(M_ref^-1 M): the position term's derivative is Jlog6 times the LOCAL
    // frame Jacobian.
    if (surface_kp)
      cd.dacc_dq.middleRows<6>(r).noalias() += kp * Jlog6(cm.reference.actInv(oMf)) * cd.Jframe;
    r += cm.dim;
  }
}

// Last step of both solves: a non-finite result is flagged, the forces go to their frames.
ContactStatus finishSolve(const Model& model, const Data& data, const ContactSet& contacts,
                          ContactData& cd, const Eigen::VectorXd& primal, Eigen::VectorXd& forces) {
  if (!primal.allFinite() || !forces.head(cd.nc).allFinite()) {
    clearOutputs(cd);
    return ContactStatus::Singular;
  }
  rotateForces(model, data, contacts, forces, nullptr, nullptr, nullptr);
  return ContactStatus::Ok;
}

}  // namespace

ContactStatus contactDynamics(const Model& model, Data& data, const ContactSet& contacts,
                              ContactData& cd, const Eigen::Ref<const Eigen::VectorXd>& q,
                              const Eigen::Ref<const Eigen::VectorXd>& v,
                              const Eigen::Ref<const Eigen::VectorXd>& tau, double damping) {
  model.checkConfiguration(q, "contactDynamics");
  model.checkVelocity(v, "contactDynamics");
  if (tau.size() != model.nv) throwSizeError("contactDynamics", "tau", model.nv, tau.size());
  checkWorkspace(model, contacts, cd, "contactDynamics");
  if (!finite(q) || !finite(v) || !finite(tau)) {
    clearOutputs(cd);
    return ContactStatus::NonFinite;
  }
  const ContactStatus status = factorKkt(model, data, contacts, cd, q, &v, damping);
  if (status != ContactStatus::Ok) return status;
  // v̇_free = M^-1 (τ - b); λ = -K^-1 (γ + Jc v̇_free); v̇ = v̇_free + Y λ.
  cd.ddq = tau - data.nle;
  solveMassMatrix(model, data, cd.ddq);
  const int nc = cd.nc;
  auto lambda = cd.lambda.head(nc);
  lambda = -cd.gamma.head(nc);
  lambda.noalias() -= cd.Jc.topRows(nc) * cd.ddq;
  solveSchur(cd, lambda);
  cd.ddq.noalias() += cd.Yt.topRows(nc).transpose() * lambda;
  return finishSolve(model, data, contacts, cd, cd.ddq, cd.lambda);
}

ContactStatus contactDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         ContactData& cd,
                                         const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         const Eigen::Ref<const Eigen::VectorXd>& tau,
                                         double damping) {
  return contactDynamicsDerivatives(model, data, contacts, cd, q, v, tau, damping, 0);
}

ContactStatus contactDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         ContactData& cd,
                                         const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         const Eigen::Ref<const Eigen::VectorXd>& tau,
                                         double damping, int tau_first, PrimalDerivatives primal) {
  if (tau_first < 0 || tau_first > model.nv)
    throwSizeError("contactDynamicsDerivatives", "tau_first", model.nv, tau_first);
  // λ comes back in each contact's force frame; the derivatives are taken in LOCAL coordinates
  // and rotated at the end (rotateForces).
  const ContactStatus status = contactDynamics(model, data, contacts, cd, q, v, tau, damping);
  if (status != ContactStatus::Ok) return status;
  contactDynamicsDerivativesAtSolution(model, data, contacts, cd, v, tau_first, primal);
  return ContactStatus::Ok;
}

void contactDynamicsDerivativesAtSolution(const Model& model, Data& data,
                                          const ContactSet& contacts, ContactData& cd,
                                          const Eigen::Ref<const Eigen::VectorXd>& v, int tau_first,
                                          PrimalDerivatives primal) {
  localForcesToJointWrenches(model, data, contacts, cd, cd.lambda);
  // R_x = ∂(RNEA(q, v, v̇) - Jc^T λ)/∂x at the solution; also the world sweep the frame
  // derivatives read. contactDynamics has just run crba(q), so data.oMi and data.J hold q's
  // kinematics: the derivative sweep reads them instead of recomputing them.
  computeRNEADerivativesFromKinematics(model, data, v, cd.ddq, cd.fext, true);
  constraintDerivatives(model, data, contacts, cd);
  kktDerivatives(model, data, contacts, cd, cd.ddq_dq, cd.lambda_dq, &cd.ddq_dv, &cd.lambda_dv,
                 &cd.ddq_dtau, &cd.lambda_dtau, tau_first, primal == PrimalDerivatives::Matrices);
  // Back to the contacts' force frames (λ itself is already rotated by contactDynamics).
  rotateForces(model, data, contacts, cd.rhs, &cd.lambda_dq, &cd.lambda_dv, &cd.lambda_dtau,
               tau_first);
}

ContactStatus impulseDynamics(const Model& model, Data& data, const ContactSet& contacts,
                              ContactData& cd, const Eigen::Ref<const Eigen::VectorXd>& q,
                              const Eigen::Ref<const Eigen::VectorXd>& v_before, double restitution,
                              double damping) {
  model.checkConfiguration(q, "impulseDynamics");
  model.checkVelocity(v_before, "impulseDynamics");
  checkWorkspace(model, contacts, cd, "impulseDynamics");
  if (!finite(q) || !finite(v_before) || !std::isfinite(restitution) || restitution < 0.0) {
    clearOutputs(cd);
    return ContactStatus::NonFinite;
  }
  const ContactStatus status = factorKkt(model, data, contacts, cd, q, nullptr, damping);
  if (status != ContactStatus::Ok) return status;
  // Jc v⁺ = -r Jc v⁻ with v⁺ = v⁻ + Y Λ:  Λ = -(1 + r) K^-1 Jc v⁻.
  const int nc = cd.nc;
  auto L = cd.impulses.head(nc);
  L.noalias() = -(1.0 + restitution) * (cd.Jc.topRows(nc) * v_before);
  solveSchur(cd, L);
  cd.v_after = v_before;
  cd.v_after.noalias() += cd.Yt.topRows(nc).transpose() * L;
  return finishSolve(model, data, contacts, cd, cd.v_after, cd.impulses);
}

ContactStatus impulseDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         ContactData& cd,
                                         const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v_before,
                                         double restitution, double damping) {
  const ContactStatus status =
      impulseDynamics(model, data, contacts, cd, q, v_before, restitution, damping);
  if (status != ContactStatus::Ok) return status;
  const int nc = cd.nc;
  // Constraint rows: ∂(Jc(q) (v⁺ + r v⁻))/∂q at fixed velocities, the derivative of the contact
  // velocity at w = v⁺ + r v⁻ (linear in w).
  // Both derivative sweeps read the kinematics of q that impulseDynamics' crba(q) left in data.
  cd.ddq = cd.v_after + restitution * v_before;  // scratch: w
  for (auto& f : cd.fext) f.setZero();
  computeRNEADerivativesFromKinematics(model, data, cd.ddq, cd.zero, cd.fext, true);
  int r = 0;
  for (int c = 0; c < contacts.size(); ++c) {
    if (!contacts.isActive(c)) continue;
    const ContactModel& cm = contacts[c];
    getFrameAccelerationDerivatives(model, data, cm.frame, cd.dv_dq, cd.dv_dv, cd.da_dq, cd.da_dv);
    cd.dacc_dq.middleRows(r, cm.dim) = cd.dv_dq.topRows(cm.dim);
    r += cm.dim;
  }
  // R_q = ∂(M(q)(v⁺ - v⁻) - Jc^T Λ)/∂q: RNEA with zero velocity, no gravity, a = v⁺ - v⁻.
  localForcesToJointWrenches(model, data, contacts, cd, cd.impulses);
  cd.ddq = cd.v_after - v_before;
  computeRNEADerivativesFromKinematics(model, data, cd.zero, cd.ddq, cd.fext, false);
  kktDerivatives(model, data, contacts, cd, cd.ddq_dq, cd.lambda_dq, nullptr, nullptr, nullptr,
                 nullptr, 0);
  // With respect to v⁻: ∂v⁺/∂v⁻ = I - (1 + r) Y K^-1 Jc,  ∂Λ/∂v⁻ = -(1 + r) K^-1 Jc.
  auto dL = cd.lambda_dv.topRows(nc);
  dL = -(1.0 + restitution) * cd.Jc.topRows(nc);
  solveSchur(cd, dL);
  cd.ddq_dv.setIdentity();
  cd.ddq_dv.noalias() += cd.Yt.topRows(nc).transpose() * dL;
  cd.ddq.setZero();
  rotateForces(model, data, contacts, cd.rhs, &cd.lambda_dq, &cd.lambda_dv, nullptr);
  return ContactStatus::Ok;
}

}  // namespace stride
