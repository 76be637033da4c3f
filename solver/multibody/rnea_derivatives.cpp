#include "solver/multibody/rnea_derivatives.hpp"

#include "solver/multibody/joint.hpp"

// Derivation (world frame; S_j the world motion subspace of dof j, λ the parent joint of j's joint,
// v, a the world spatial velocity and acceleration of a body, a_0 = -g; "i ⪰ j" when dof i belongs
// to the subtree of dof j's joint, its own joint included).
//
// Moving q_j turns j's subtree by S_j: ∂S_k/∂q_j = S_j x S_k, and the velocity and acceleration
// of a body k of that subtree change by
//   ∂v_k/∂q_j = S_j x v_k + w_j,                 w_j = -S_j x v_λ
//   ∂a_k/∂q_j = S_j x a_k + u_j + w_j x (v_k - v_λ),  u_j = -S_j x a_λ.
// A pure turn of everything (S x on motions, S x* on forces, Y -> S x* Y - Y S x) maps the body
// force f = Y a + v x* (Y v) to S x* f, so only the extra terms remain. With Ẏ = v x* Y - Y v x
// they sum over a subtree to
//   ∂F_i/∂q_j = S_j x* F_i + Y_i c_j + Ẏ_i w_j + w_j x* h_i,     c_j = u_j - w_j x v_λ,
// where F_i, Y_i, Ẏ_i, h_i = Σ Y v are the composite force, inertia, inertia rate and momentum
// of the subtree of dof i. Because <S x m, f> + <m, S x* f> = 0, for τ_i = S_i . F_i:
//   i ⪰ j:  ∂τ_i/∂q_j = A_i . c_j + B_i . w_j,   A_i = Y_i S_i,  B_i = Ẏ_i^T S_i - S_i x* h_i
//   i ≺ j:  ∂τ_i/∂q_j = S_i . G_j,               G_j = S_j x* F_j + Y_j c_j + Ẏ_j w_j + w_j x* h_j
// The same steps for the joint rates (∂v_k/∂q̇_j = S_j, ∂a_k/∂q̇_j = S_j x v_k + e_j with
// e_j = (v_λ + v_J) x S_j, v_J the spatial velocity of the body of j's own joint, not its joint
// rate S_j q̇_j) give
//   i ⪰ j:  ∂τ_i/∂v_j = A_i . e_j + B_i . S_j
//   i ≺ j:  ∂τ_i/∂v_j = S_i . H_j,               H_j = Ẏ_j S_j + Y_j e_j + S_j x* h_j.
// Every entry is one 6-vector dot product over pairs of dofs on a common path, like the CRBA.

namespace stride {

namespace {

// Ẏ = [v x*] Y - Y [v x] for a body inertia Y = [m Id, -[h]x; [h]x, I] moving with v = [ν; ω].
// Y keeps that form at every instant (in the world frame only its h and I change), so Ẏ is
// symmetric with the same structure and zero mass: Ẏ = [0, -[ḣ]x; [ḣ]x, İ] with
//   ḣ = m ν + ω x h,   İ = X + X^T,   X = [ω]x I - h ν^T + (ν . h) Id
// (from [ν]x[h]x + [h]x[ν]x = h ν^T + ν h^T - 2 (ν . h) Id). Stored as an Inertia with m = 0: it
// sums over a subtree like an inertia, and applying it costs a third of a 6x6 product.
Inertia inertiaRate(const Eigen::Vector3d& nu, const Eigen::Vector3d& w, const Inertia& Y) {
  Inertia r;
  r.m = 0.0;
  r.h = Y.m * nu + w.cross(Y.h);
  Eigen::Matrix3d X;
  X.noalias() = skew(w) * Y.I;
  X.noalias() -= Y.h * nu.transpose();
  X.diagonal().array() += nu.dot(Y.h);
  r.I = X + X.transpose();
  return r;
}

inline double dot6(const double* a, const Vector6d& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5];
}

}  // namespace

namespace {
// kReuse: data.oMi and data.J already hold the placements and world motion subspaces for this q
// (q is then not read).
template <bool kReuse>
void rneaDerivatives(const Model& model, Data& data, const double* q,
                     const Eigen::Ref<const Eigen::VectorXd>& v,
                     const Eigen::Ref<const Eigen::VectorXd>& a, const std::vector<Vector6d>* fext,
                     bool with_gravity) {
  model.checkVelocity(v, "computeRNEADerivatives");
  if (a.size() != model.nv) throwSizeError("computeRNEADerivatives", "a", model.nv, a.size());
  const int n = model.njoints();
  if (fext && static_cast<int>(fext->size()) != n)
    throwSizeError("computeRNEADerivatives", "fext", n, static_cast<long>(fext->size()));

  // Forward sweep: world placements, subspaces, velocities, accelerations (gravity included), the
  // per-dof vectors w, c, e, and each body's inertia, inertia rate, momentum and force.
  data.ov[0].setZero();
  // An external force turns with its body, like the body's own force: it simply joins the
  // composite force F (the derivation above holds for f - f_ext).
  data.oa[0].head<3>() = with_gravity ? Eigen::Vector3d(-model.gravity) : Eigen::Vector3d::Zero();
  data.oa[0].tail<3>().setZero();
  for (int i = 1; i < n; ++i) {
    const Joint& j = model.joints[i];
    auto S = data.J.middleCols(j.idx_v, j.nv);
    if constexpr (!kReuse) {
      jointPlacement(j, q + j.idx_q, data.liMi[i]);
      data.oMi[i] = data.oMi[j.parent] * data.liMi[i];
      if (j.type == JointType::FreeFlyer)
        S = data.oMi[i].toActionMatrix();
      else
        S.col(0) = jointSubspaceWorld(j, data.oMi[i]);
    }
    const SE3& oMi = data.oMi[i];
    // In 3-vector halves, as the backward sweep (motion cross: a x b = [a_a x b_l + a_l x b_a;
    // a_a x b_a]); v_i and a_i stay in registers for the rest of the step.
    Eigen::Vector3d vJ_l, vJ_a, aJ_l, aJ_a;
    if (j.nv == 1) {
      const double vk = v[j.idx_v], ak = a[j.idx_v];
      vJ_l = S.col(0).head<3>() * vk;
      vJ_a = S.col(0).tail<3>() * vk;
      aJ_l = S.col(0).head<3>() * ak;
      aJ_a = S.col(0).tail<3>() * ak;
    } else {
      const Vector6d vJ = S * v.segment(j.idx_v, j.nv), aJ = S * a.segment(j.idx_v, j.nv);
      vJ_l = vJ.head<3>();
      vJ_a = vJ.tail<3>();
      aJ_l = aJ.head<3>();
      aJ_a = aJ.tail<3>();
    }
    const Vector6d& vp = data.ov[j.parent];
    const Vector6d& ap = data.oa[j.parent];
    const Eigen::Vector3d vp_l = vp.head<3>(), vp_a = vp.tail<3>(), ap_l = ap.head<3>(),
                          ap_a = ap.tail<3>();
    const Eigen::Vector3d v_l = vp_l + vJ_l, v_a = vp_a + vJ_a;
    const Eigen::Vector3d a_l = ap_l + aJ_l + v_a.cross(vJ_l) + v_l.cross(vJ_a);
    const Eigen::Vector3d a_a = ap_a + aJ_a + v_a.cross(vJ_a);
    data.ov[i].head<3>() = v_l;
    data.ov[i].tail<3>() = v_a;
    data.oa[i].head<3>() = a_l;
    data.oa[i].tail<3>() = a_a;
    const Eigen::Vector3d vs_l = vp_l + v_l, vs_a = vp_a + v_a;
    for (int k = 0; k < j.nv; ++k) {
      const Eigen::Vector3d S_l = S.col(k).head<3>(), S_a = S.col(k).tail<3>();
      const int d = j.idx_v + k;
      // w = v_λ x S (= -S x v_λ), c = a_λ x S - w x v_λ, e = (v_λ + v_i) x S.
      const Eigen::Vector3d w_l = vp_a.cross(S_l) + vp_l.cross(S_a), w_a = vp_a.cross(S_a);
      data.dW.col(d).head<3>() = w_l;
      data.dW.col(d).tail<3>() = w_a;
      data.dC.col(d).head<3>() =
          ap_a.cross(S_l) + ap_l.cross(S_a) - w_a.cross(vp_l) - w_l.cross(vp_a);
      data.dC.col(d).tail<3>() = ap_a.cross(S_a) - w_a.cross(vp_a);
      data.dE.col(d).head<3>() = vs_a.cross(S_l) + vs_l.cross(S_a);
      data.dE.col(d).tail<3>() = vs_a.cross(S_a);
    }
    const Inertia oY = kReuse ? data.oYbody[i] : model.inertias[i].transformedBy(oMi);
    data.oYcrb[i] = oY;
    // h = Y v, F = Y a + v x* h - f_ext.
    const Eigen::Vector3d h_l = oY.m * v_l - oY.h.cross(v_a), h_a = oY.I * v_a + oY.h.cross(v_l);
    data.oh[i].head<3>() = h_l;
    data.oh[i].tail<3>() = h_a;
    data.oF[i].head<3>() = oY.m * a_l - oY.h.cross(a_a) + v_a.cross(h_l);
    data.oF[i].tail<3>() = oY.I * a_a + oY.h.cross(a_l) + v_a.cross(h_a) + v_l.cross(h_l);
    if (fext) data.oF[i] -= oMi.actForce((*fext)[i]);
    data.oBcrb[i] = inertiaRate(v_l, v_a, oY);
  }

  // Backward sweep: with the subtree of joint i complete, the per-dof vectors A, B, G, H of its
  // dofs, then the entries of the columns of its dofs, then accumulation into the parent.
  Eigen::MatrixXd& dq = data.dtau_dq;
  Eigen::MatrixXd& dv = data.dtau_dv;
  for (int i = n - 1; i > 0; --i) {
    const Joint& j = model.joints[i];
    const Inertia& Y = data.oYcrb[i];
    const Inertia& B = data.oBcrb[i];
    const Vector6d& h = data.oh[i];
    const Vector6d& F = data.oF[i];
    // In 3-vector halves ([linear; angular]) with the products written out: built from 6-vector
    // temporaries, every sum stored its halves to the stack and reloaded them whole, stalling on
    // store forwarding.
    const Eigen::Vector3d h_l = h.head<3>(), h_a = h.tail<3>(), F_l = F.head<3>(),
                          F_a = F.tail<3>();
    // Y x = [m x_l - hY x x_a; I x_a + hY x x_l]; Ẏ x the same with m = 0.
    auto mulY = [&Y](const Eigen::Vector3d& l, const Eigen::Vector3d& a, Eigen::Vector3d& out_l,
                     Eigen::Vector3d& out_a) {
      out_l = Y.m * l - Y.h.cross(a);
      out_a.noalias() = Y.I * a;
      out_a += Y.h.cross(l);
    };
    auto mulB = [&B](const Eigen::Vector3d& l, const Eigen::Vector3d& a, Eigen::Vector3d& out_l,
                     Eigen::Vector3d& out_a) {
      out_l = -B.h.cross(a);
      out_a.noalias() = B.I * a;
      out_a += B.h.cross(l);
    };
    for (int k = j.idx_v; k < j.idx_v + j.nv; ++k) {
      const Eigen::Vector3d S_l = data.J.col(k).head<3>(), S_a = data.J.col(k).tail<3>();
      const Eigen::Vector3d w_l = data.dW.col(k).head<3>(), w_a = data.dW.col(k).tail<3>();
      const Eigen::Vector3d c_l = data.dC.col(k).head<3>(), c_a = data.dC.col(k).tail<3>();
      const Eigen::Vector3d e_l = data.dE.col(k).head<3>(), e_a = data.dE.col(k).tail<3>();
      data.tau[k] = S_l.dot(F_l) + S_a.dot(F_a);
      // Ẏ is symmetric: Ẏ^T S = Ẏ S serves B and H. S x* h = [S_a x h_l; S_a x h_a + S_l x h_l].
      Eigen::Vector3d BS_l, BS_a, A_l, A_a, Yc_l, Yc_a, Bw_l, Bw_a, Ye_l, Ye_a;
      mulB(S_l, S_a, BS_l, BS_a);
      mulY(S_l, S_a, A_l, A_a);
      mulY(c_l, c_a, Yc_l, Yc_a);
      mulB(w_l, w_a, Bw_l, Bw_a);
      mulY(e_l, e_a, Ye_l, Ye_a);
      const Eigen::Vector3d Sh_l = S_a.cross(h_l), Sh_a = S_a.cross(h_a) + S_l.cross(h_l);
      auto dA = data.dA.col(k);
      auto dB = data.dB.col(k);
      auto dG = data.dG.col(k);
      auto dH = data.dH.col(k);
      dA.head<3>() = A_l;
      dA.tail<3>() = A_a;
      dB.head<3>() = BS_l - Sh_l;
      dB.tail<3>() = BS_a - Sh_a;
      // G = S x* F + Y c + w x* h + Ẏ w
      dG.head<3>() = S_a.cross(F_l) + Yc_l + w_a.cross(h_l) + Bw_l;
      dG.tail<3>() =
          S_a.cross(F_a) + S_l.cross(F_l) + Yc_a + w_a.cross(h_a) + w_l.cross(h_l) + Bw_a;
      // H = Y e + S x* h + Ẏ S
      dH.head<3>() = Ye_l + Sh_l + BS_l;
      dH.tail<3>() = Ye_a + Sh_a + BS_a;
    }
    const int first = j.idx_v, end = first + model.nvSubtree[first];
    for (int col = first; col < first + j.nv; ++col) {
      const Vector6d c = data.dC.col(col), w = data.dW.col(col), e = data.dE.col(col),
                     Sj = data.J.col(col), G = data.dG.col(col), H = data.dH.col(col);
      // Rows in the subtree (this joint's dofs included).
      for (int r = first; r < end; ++r) {
        const double* A = data.dA.col(r).data();
        const double* Bv = data.dB.col(r).data();
        dq(r, col) = dot6(A, c) + dot6(Bv, w);
        dv(r, col) = dot6(A, e) + dot6(Bv, Sj);
      }
      // Rows of the strict ancestors.
      for (int r = model.parentDof[first]; r >= 0; r = model.parentDof[r]) {
        const double* Sr = data.J.col(r).data();
        dq(r, col) = dot6(Sr, G);
        dv(r, col) = dot6(Sr, H);
      }
    }
    if (j.parent > 0) {
      data.oYcrb[j.parent] += Y;
      data.oBcrb[j.parent] += B;
      data.oh[j.parent] += h;
      data.oF[j.parent] += F;
    }
  }
}
}  // namespace

void computeRNEADerivatives(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& v,
                            const Eigen::Ref<const Eigen::VectorXd>& a) {
  model.checkConfiguration(q, "computeRNEADerivatives");
  rneaDerivatives<false>(model, data, q.data(), v, a, nullptr, true);
}

void computeRNEADerivatives(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& v,
                            const Eigen::Ref<const Eigen::VectorXd>& a,
                            const std::vector<Vector6d>& fext, bool with_gravity) {
  model.checkConfiguration(q, "computeRNEADerivatives");
  rneaDerivatives<false>(model, data, q.data(), v, a, &fext, with_gravity);
}

void computeRNEADerivativesFromKinematics(const Model& model, Data& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& v,
                                          const Eigen::Ref<const Eigen::VectorXd>& a,
                                          const std::vector<Vector6d>& fext, bool with_gravity) {
  rneaDerivatives<true>(model, data, nullptr, v, a, &fext, with_gravity);
}

void computeRNEADerivativesFromKinematics(const Model& model, Data& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& v,
                                          const Eigen::Ref<const Eigen::VectorXd>& a) {
  rneaDerivatives<true>(model, data, nullptr, v, a, nullptr, true);
}

}  // namespace stride
