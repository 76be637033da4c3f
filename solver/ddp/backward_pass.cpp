#include "solver/ddp/solver.hpp"

#include <algorithm>
#include <cmath>

#include "solver/multibody/cholesky.hpp"

namespace stride {

namespace {
// The Euler-structured products have half the flops of the dense ones but more, smaller
// operations. Measured (100 knots, median of 5, interleaved runs) with the products through the
// velocity rows G, H: anymal and hyq (nv 18) 1.20-1.32 ms per backward pass against 1.30-1.43
// dense; solo (nv 14) 0.71-0.72 against 0.67-0.72. So the structured route runs from nv = 16.
// Again with the fused products below (issue 35, min of 9 interleaved runs): solo 0.487 ms
// structured against 0.441 dense, hyq 0.760 structured (0.792 before the fusion).
constexpr int kStructureMinNv = 16;

// Copies a square matrix's lower triangle to its upper one.
void mirrorLower(Eigen::MatrixXd& A) {
  const int n = static_cast<int>(A.rows());
  for (int j = 0; j < n; ++j)
    for (int i = j + 1; i < n; ++i) A(j, i) = A(i, j);
}
}  // namespace

// Qxx, Qxu, Quu through the Euler structure (action.hpp): Fx = E + B G, Fu = B H with
// E = [Jq 0; 0 0], B = [dt Jv; I] and G, H the velocity rows of Fx, Fu (the knot's own results).
// With V the regularized next value Hessian, V Fx = [V_q Jq, 0] + (V B) G and
// Fxᵀ Y = [Jqᵀ Y_q; 0] + Gᵀ (Bᵀ Y), where products with Jq, Jv cost O(n²) (identities but for one
// 6 x 6 block) and only the products with G (nv x 2nv) and H (nv x nu) are dense: half the flops of
// Fxᵀ V Fx formed directly. Each identity part is one pass that combines its terms where they
// land, and each 6 x 6 block one small product into its rows or columns: no block is copied to
// a scratch and back (issue 35: a third less time outside the products).
void Solver::eulerProducts(const ActionData& d, int nu) {
  const EulerStructure& e = d.euler;
  const int n = ndx_ / 2, nb = e.nb, nj = n - nb;  // nb: 0 or 6 (a free-flyer's block)
  const double dt = e.dt;
  const Eigen::MatrixXd& V = Vxx_next_;
  const auto G = d.Fx.bottomRows(n);
  const Matrix6d dtJv = dt * e.Jv;
  // VB = V B = dt V_q Jv + V_v (2n x n).
  auto VB = VB_.leftCols(n);
  VB.rightCols(nj) = dt * V.middleCols(nb, nj) + V.rightCols(nj);
  if (nb) {
    VB.leftCols<6>() = V.middleCols<6>(n);
    VB.leftCols<6>().noalias() += V.leftCols<6>() * dtJv;
  }
  // V Fx = [V_q Jq, 0] + VB G.
  VFx_.noalias() = VB * G;
  VFx_.middleCols(nb, nj) += V.middleCols(nb, nj);
  if (nb) VFx_.leftCols<6>().noalias() += V.leftCols<6>() * e.Jq;
  // Bᵀ V Fx = dt Jvᵀ (V Fx)_q + (V Fx)_v (n x 2n).
  auto BtVFx = BtY_.leftCols(ndx_);
  BtVFx.bottomRows(nj) = dt * VFx_.middleRows(nb, nj) + VFx_.bottomRows(nj);
  if (nb) {
    BtVFx.topRows<6>() = VFx_.middleRows<6>(n);
    BtVFx.topRows<6>().noalias() += dtJv.transpose() * VFx_.topRows<6>();
  }
  // Qxx = Lxx + [Jqᵀ (V Fx)_q; 0] + Gᵀ Bᵀ V Fx. It is symmetric: its lower triangle is the sum of
  // its terms' lower triangles.
  Qxx_ = d.Lxx;
  Qxx_.middleRows(nb, nj) += VFx_.middleRows(nb, nj);
  if (nb) Qxx_.topRows<6>().noalias() += e.Jq.transpose() * VFx_.topRows<6>();
  Qxx_.triangularView<Eigen::Lower>() += G.transpose() * BtVFx;
  if (nu == 0) return;
  // V Fu = VB H; Qxu = Lxu + [Jqᵀ (V Fu)_q; 0] + Gᵀ Bᵀ V Fu; Quu = Luu + Hᵀ Bᵀ V Fu.
  const auto H = d.Fu.bottomRows(n);
  auto VFu = VFu_.leftCols(nu);
  VFu.noalias() = VB * H;
  auto BtVFu = BtY_.leftCols(nu);
  BtVFu.bottomRows(nj) = dt * VFu.middleRows(nb, nj) + VFu.bottomRows(nj);
  if (nb) {
    BtVFu.topRows<6>() = VFu.middleRows<6>(n);
    BtVFu.topRows<6>().noalias() += dtJv.transpose() * VFu.topRows<6>();
  }
  auto Qxu = Qxu_.leftCols(nu);
  Qxu = d.Lxu;
  Qxu.middleRows(nb, nj) += VFu.middleRows(nb, nj);
  if (nb) Qxu.topRows<6>().noalias() += e.Jq.transpose() * VFu.topRows<6>();
  Qxu.noalias() += G.transpose() * BtVFu;
  auto Quu = Quu_.topLeftCorner(nu, nu);
  Quu = d.Luu;
  Quu.noalias() += H.transpose() * BtVFu;
}

bool Solver::backwardPass(Clock::time_point deadline) {
  backward_next_ = -1;
  return backward(deadline);
}

bool Solver::backward(Clock::time_point deadline) {
  PieceGuard piece{*this};  // its start moves to each deadline check: a piece per chunk
  backward_nonfinite_ = false;
  cut_ = false;
  const bool box = kind_ == SolverKind::BoxFddp && has_bounds_;
  if (backward_next_ < 0) {  // a new pass; else one its deadline cut resumes at backward_next_
    ++backward_passes_;
    const ActionData& dT = problem_.terminalData();
    Vx_next_ = dT.Lx;
    Vxx_next_ = dT.Lxx;
    backward_next_ = T_ - 1;
  }
  // Any exit but the cut below ends the pass (a failed one starts again at its retry).
  const int first = backward_next_;
  backward_next_ = -1;
  for (int k = first; k >= 0; --k) {
    if (k != first && (first - k) % kDeadlineKnots == 0) {
      pieceDone(piece.start);
      piece.start = Clock::now();
      if (piece.start >= deadline) {  // Vx_next_, Vxx_next_ hold knot k + 1's value
        cut_ = true;
        backward_next_ = k;
        return false;
      }
    }
    const ActionData& d = problem_.data(k);
    const int nu = problem_.nu(k);
    // The value of the next knot seen from this one: V'x = Vx + Vxx f (the gap, FDDP), and Vxx
    // regularized by μ I (Tassa et al.: a trust region on the state).
    Vx_gap_ = Vx_next_;
    if (tail_gap_ >= options.gap_tolerance) Vx_gap_.noalias() += Vxx_next_ * fs_[k + 1];
    Vxx_next_.diagonal().array() += reg_;
    // Gauss-Newton Q terms (eq. 12): the knot's cost Hessian plus the value propagated through
    // the dynamics' Jacobians.
    const bool euler = d.euler.valid && options.exploit_structure && ndx_ / 2 >= kStructureMinNv;
    if (euler) {
      eulerProducts(d, nu);
    } else {
      VFx_.noalias() = Vxx_next_ * d.Fx;
      Qxx_ = d.Lxx;
      Qxx_.triangularView<Eigen::Lower>() += d.Fx.transpose() * VFx_;
    }
    Qx_ = d.Lx;
    Qx_.noalias() += d.Fx.transpose() * Vx_gap_;
    // V starts from Q (Qx, Qxx are not read again): traded, not copied.
    Vx_.swap(Qx_);
    Vxx_.swap(Qxx_);
    if (nu > 0) {
      auto VFu = VFu_.leftCols(nu);
      auto Quu = Quu_.topLeftCorner(nu, nu);
      auto Qxu = Qxu_.leftCols(nu);
      auto W = W_.topRows(nu);
      auto Qu = Qu_.head(nu);
      Eigen::VectorXd& kk = k_[k];
      Eigen::MatrixXd& KK = K_[k];
      if (!euler) {
        VFu.noalias() = Vxx_next_ * d.Fu;
        Quu = d.Luu;
        Quu.noalias() += d.Fu.transpose() * VFu;
        Qxu = d.Lxu;
        Qxu.noalias() += d.Fx.transpose() * VFu;
      }
      Quu.diagonal().array() += reg_;  // Levenberg-Marquardt
      Qu = d.Lu;
      Qu.noalias() += d.Fu.transpose() * Vx_gap_;
      if (box) {
        // k: the box QP on the control step (bounds shifted by the current control), warm
        // started from the last k; K on the free controls only, zero on the clamped ones.
        BoxQP& qp = box_;
        auto lb = w_.head(nu);
        lb = u_lower_.head(nu) - us_[k];
        du_.head(nu) = u_upper_.head(nu) - us_[k];
        if (!qp.solve(Quu, Qu, lb, du_.head(nu), kk)) return false;
        // K_F = -H_FF^-1 Qxu_Fᵀ through H_FF^-1 formed from the QP's factor, as in the
        // unconstrained branch: Eigen's blocked triangular solves on 2nv right-hand sides were
        // ~7% of the quadruped's backward pass, mostly setup.
        const int nf = qp.nfree();
        const Eigen::VectorXi& F = qp.freeIndices();
        inverseFromCholesky(qp.freeFactor(), nf, Quu_inv_);
        const auto Hinv = Quu_inv_.topLeftCorner(nf, nf);
        if (nf == nu) {
          KK.noalias() = Hinv * Qxu.transpose();  // F is 0..nu-1 in order
          KK = -KK;                               // negated after the product: see below
        } else {
          auto Wf = W.topRows(nf);
          for (int a = 0; a < nf; ++a) Wf.row(a) = Qxu.col(F[a]).transpose();
          auto Kf = Wf_.topRows(nf);
          // Negated after the product: with one free control (nf = 1) Eigen takes its
          // row-vector path, which copied the negated row `(-Hinv).row(0)` into a heap
          // temporary (tests/ocp/test_solver_no_alloc.cpp, BoxFddpWithOneFreeControl).
          Kf.noalias() = Hinv * Wf;
          Kf = -Kf;
          KK.setZero();
          for (int a = 0; a < nf; ++a) KK.row(F[a]) = Kf.row(a);
        }
      } else {
        Eigen::Ref<Eigen::MatrixXd> Quu_ref(Quu);
        Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(Quu_ref);  // in place
        if (llt.info() != Eigen::Success) return false;
        // Quu^-1 explicitly (nu columns through the factor), then k and K by products: the
        // triangular solves on the ndx + 1 right-hand sides cost more than the products at these
        // sizes.
        inverseFromCholesky(Quu_, nu, Quu_inv_);
        const auto Quu_inv = Quu_inv_.topLeftCorner(nu, nu);
        // Negated after the products, as in the box branch (no heap temporary when nu = 1).
        kk.noalias() = Quu_inv * Qu;
        kk = -kk;
        KK.noalias() = Quu_inv * Qxu.transpose();
        KK = -KK;
      }
      // At the (box-)QP solution Kᵀ(Qu + Quu k) = 0 and Kᵀ(Qux + Quu K) = 0 on the free set, so
      // V'x = Qx + Qxu k and V'xx = Qxx + Qxu K for both branches.
      Vx_.noalias() += Qxu * kk;
      Vxx_.triangularView<Eigen::Lower>() += Qxu * KK;
    }
    // Only the lower triangles of Qxx and Vxx are formed (half the products): mirrored here.
    mirrorLower(Vxx_);
    Vx_next_.swap(Vx_);
    Vxx_next_.swap(Vxx_);
  }
  if (!Vx_next_.allFinite() || !Vxx_next_.allFinite()) {
    backward_nonfinite_ = true;
    return false;
  }
  return true;
}

}  // namespace stride
