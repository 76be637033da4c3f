#include "solver/ddp/solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace stride {

namespace {
// μ never restarts from 0 when raised, so the retries of a failed backward pass are bounded.
constexpr double kRegFloor = 1e-9;
// The Euler-structured products have half the flops of the dense ones but more, smaller
// operations. Measured (100 knots, median of 5, interleaved runs) with the products through the
// velocity rows G, H: anymal and hyq (nv 18) 1.20-1.32 ms per backward pass against 1.30-1.43
// dense; solo (nv 14) 0.71-0.72 against 0.67-0.72. So the structured route runs from nv = 16.
constexpr int kStructureMinNv = 16;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A^-1 (n x n, top-left of X) from the Cholesky factor L of A in the lower triangle of the top-left
// n x n of L: L^-1 by forward substitution, then A^-1 = L^-T L^-1. Plain loops: at a dozen rows
// Eigen's blocked triangular solves spend more time in their setup than in the arithmetic (two
// solves were 5% of solo's backward pass).
void invertFromCholesky(const Eigen::MatrixXd& L, int n, Eigen::MatrixXd& X) {
  // The reciprocal pivots first (X's diagonal): a division inside the loop would sit on its
  // dependency chain.
  for (int j = 0; j < n; ++j) X(j, j) = 1.0 / L(j, j);
  for (int j = 0; j < n; ++j)
    for (int i = j + 1; i < n; ++i) {
      double s = 0.0;
      for (int k = j; k < i; ++k) s -= L(i, k) * X(k, j);
      X(i, j) = s * X(i, i);
    }
  // (L^-T L^-1)(i, j) = Σ_{k >= max(i, j)} X(k, i) X(k, j); the upper triangle first, so that the
  // lower one still holds L^-1 while it is read.
  for (int j = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i) {
      double s = 0.0;
      for (int k = j; k < n; ++k) s += X(k, i) * X(k, j);
      X(i, j) = s;
    }
  for (int j = 0; j < n; ++j)
    for (int i = j + 1; i < n; ++i) X(i, j) = X(j, i);
}

// Copies a square matrix's lower triangle to its upper one.
void mirrorLower(Eigen::MatrixXd& A) {
  const int n = static_cast<int>(A.rows());
  for (int j = 0; j < n; ++j)
    for (int i = j + 1; i < n; ++i) A(j, i) = A(i, j);
}
}  // namespace

const char* toString(SolveStatus status) {
  switch (status) {
    case SolveStatus::Converged:
      return "converged";
    case SolveStatus::MaxIterations:
      return "iteration limit";
    case SolveStatus::Deadline:
      return "deadline";
    case SolveStatus::NoDescent:
      return "no descent (regularization limit)";
    case SolveStatus::NonFinite:
      return "non-finite value";
  }
  return "?";
}

Solver::Solver(ShootingProblem& problem, SolverKind kind, const SolverOptions& opts)
    : options(opts),
      problem_(problem),
      kind_(kind),
      T_(problem.horizon()),
      ndx_(problem.ndx()),
      box_(problem.maxNu()) {
  const int nx = problem.nx(), m = problem.maxNu(), n = ndx_;
  xs_.assign(T_ + 1, problem.x0());
  xs_try_ = xs_;
  fs_.assign(T_ + 1, Eigen::VectorXd::Zero(n));
  for (int k = 0; k < T_; ++k) {
    const int nu = problem.nu(k);
    us_.push_back(Eigen::VectorXd::Zero(nu));
    k_.push_back(Eigen::VectorXd::Zero(nu));
    K_.push_back(Eigen::MatrixXd::Zero(nu, n));
  }
  us_try_ = us_;
  K_old_ = K_;
  Vx_next_ = Vx_ = Vx_gap_ = Qx_ = Eigen::VectorXd::Zero(n);
  Vxx_next_ = Vxx_ = Qxx_ = VFx_ = Eigen::MatrixXd::Zero(n, n);
  Qxu_ = VFu_ = Eigen::MatrixXd::Zero(n, m);
  Quu_ = Quu_inv_ = Eigen::MatrixXd::Zero(m, m);
  VB_ = Eigen::MatrixXd::Zero(n, n / 2);
  BtY_ = EtY_ = Eigen::MatrixXd::Zero(n / 2, std::max(n, m));
  colwork_ = Eigen::Matrix<double, Eigen::Dynamic, 6>::Zero(n, 6);
  rowwork_ = Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, std::max(n, m));
  W_ = Wf_ = Eigen::MatrixXd::Zero(m, n);
  Qu_ = Eigen::VectorXd::Zero(m);
  w_ = Eigen::VectorXd::Zero(m);
  dx_ = dx_next_ = tmp_x_ = Eigen::VectorXd::Zero(n);
  du_ = Eigen::VectorXd::Zero(m);
  u_lower_ = Eigen::VectorXd::Constant(m, -kInfinity);
  u_upper_ = Eigen::VectorXd::Constant(m, kInfinity);
  stats_.resize(kMaxStats);
  reg_ = options.reg_initial;
  x_last_ = Eigen::VectorXd::Zero(nx);
  u_last_ = Eigen::VectorXd::Zero(problem.nu(T_ - 1));
  K_last_ = Eigen::MatrixXd::Zero(problem.nu(T_ - 1), n);
}

void Solver::setControlBounds(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  const int m = problem_.maxNu();
  if (lower.size() != m || upper.size() != m)
    throw std::invalid_argument("Solver::setControlBounds: bounds must have size " +
                                std::to_string(m));
  if ((lower.array() > upper.array()).any())
    throw std::invalid_argument("Solver::setControlBounds: a lower bound exceeds its upper bound");
  u_lower_ = lower;
  u_upper_ = upper;
  has_bounds_ = true;
}

bool Solver::setWarmStart(const std::vector<Eigen::VectorXd>& xs,
                          const std::vector<Eigen::VectorXd>& us) {
  if (static_cast<int>(xs.size()) != T_ + 1 || static_cast<int>(us.size()) != T_) return false;
  for (int k = 0; k <= T_; ++k)
    if (xs[k].size() != problem_.nx() || !xs[k].allFinite()) return false;
  for (int k = 0; k < T_; ++k)
    if (us[k].size() != problem_.nu(k) || !us[k].allFinite()) return false;
  for (int k = 0; k <= T_; ++k) xs_[k] = xs[k];
  for (int k = 0; k < T_; ++k) us_[k] = us[k];
  feasible_ = false;
  discardPreparation();
  return true;
}

void Solver::shiftWarmStart(int n) {
  n = std::clamp(n, 0, T_);
  if (n == 0) return;
  // The new tail repeats the last state, control and gain of the old trajectory (saved first: a
  // shift by T rotates nothing).
  x_last_ = xs_[T_];
  const bool uniform = us_[T_ - 1].size() == u_last_.size();
  if (uniform) {
    u_last_ = us_[T_ - 1];
    K_last_ = K_[T_ - 1];
  }
  // Rotations swap the vectors' buffers: no allocation.
  std::rotate(xs_.begin(), xs_.begin() + n % (T_ + 1), xs_.end());
  std::rotate(us_.begin(), us_.begin() + n % T_, us_.end());
  std::rotate(K_.begin(), K_.begin() + n % T_, K_.end());
  std::rotate(k_.begin(), k_.begin() + n % T_, k_.end());
  for (int k = T_ + 1 - n; k <= T_; ++k) xs_[k] = x_last_;
  for (int k = T_ - n; k < T_; ++k)
    if (uniform && us_[k].size() == u_last_.size()) {
      us_[k] = u_last_;
      K_[k] = K_last_;
    }
  feasible_ = false;
  discardPreparation();
}

void Solver::retimeWarmStart(const std::vector<double>& from, const std::vector<double>& to) {
  if (static_cast<int>(from.size()) != T_ + 1 || static_cast<int>(to.size()) != T_ + 1) return;
  constexpr double eps = 1e-9;  // grid times are sums of durations: equal up to rounding
  bool same = true;
  for (int k = 0; k <= T_ && same; ++k) same = std::abs(from[k] - to[k]) <= eps;
  if (same) return;
  // The old trajectory goes to the line search's buffers (rewritten by every rollout).
  for (int k = 0; k <= T_; ++k) xs_try_[k] = xs_[k];
  for (int k = 0; k < T_; ++k) {
    us_try_[k] = us_[k];
    K_old_[k] = K_[k];
  }
  const StateSpace& space = problem_.state();
  const auto control = [&](int k, int j) {  // new knot k takes old knot j's control and gain
    j = std::min(j, T_ - 1);
    if (k < T_ && us_[k].size() == us_try_[j].size()) {
      us_[k] = us_try_[j];
      K_[k] = K_old_[j];
    }
  };
  int j = 0;  // the first old knot at or after the new knot's time
  for (int k = 0; k <= T_; ++k) {
    const double t = to[k];
    while (j <= T_ && from[j] < t - eps) ++j;
    if (j > T_) {  // past the old end
      xs_[k] = xs_try_[T_];
      control(k, T_ - 1);
    } else if (from[j] <= t + eps) {  // an old knot at this time
      int src = j;
      if (k > 0 && to[k] - to[k - 1] <= eps)  // after an impulse knot: the post-impact state
        while (src < T_ && from[src + 1] <= t + eps) ++src;
      xs_[k] = xs_try_[src];
      control(k, src);
    } else if (j == 0) {  // before the old start
      xs_[k] = xs_try_[0];
      control(k, 0);
    } else {  // between old knots a = j - 1 (the post-impact one of a pair) and j
      const int a = j - 1;
      const double s = (t - from[a]) / (from[j] - from[a]);
      space.difference(xs_try_[a], xs_try_[j], dx_);
      dx_ *= s;
      space.integrate(xs_try_[a], dx_, xs_[k]);
      control(k, s < 0.5 ? a : j);
      if (k < T_ && j < T_ && us_[k].size() == us_try_[a].size() &&
          us_[k].size() == us_try_[j].size())
        us_[k] = (1.0 - s) * us_try_[a] + s * us_try_[j];
    }
  }
  feasible_ = false;
  discardPreparation();
}

bool Solver::setControl(int k, const Eigen::VectorXd& u) {
  if (k < 0 || k >= T_ || u.size() != us_[k].size() || !u.allFinite()) return false;
  us_[k] = u;
  feasible_ = false;
  discardPreparation();
  return true;
}

bool Solver::finiteTrajectory() const {
  for (const auto& x : xs_)
    if (!x.allFinite()) return false;
  for (const auto& u : us_)
    if (!u.allFinite()) return false;
  return true;
}

bool Solver::rollout() {
  // Into the trial trajectory, swapped in only when every knot succeeded: a failure keeps the
  // last good iterate.
  xs_try_[0] = problem_.x0();
  double cost = 0.0;
  for (int k = 0; k < T_; ++k) {
    us_try_[k] = us_[k];
    if (has_bounds_ && kind_ == SolverKind::BoxFddp) {
      const int nu = problem_.nu(k);
      us_try_[k] = us_try_[k].cwiseMax(u_lower_.head(nu)).cwiseMin(u_upper_.head(nu));
    }
    ActionData& d = problem_.data(k);
    problem_.knot(k).calc(d, xs_try_[k], us_try_[k]);
    if (d.status != KnotStatus::Ok) return false;
    cost += d.cost;
    xs_try_[k + 1] = d.x_next;
  }
  ActionData& dT = problem_.terminalData();
  problem_.terminal().calc(dT, xs_try_[T_], Eigen::VectorXd());
  if (dT.status != KnotStatus::Ok || !std::isfinite(cost + dT.cost)) return false;
  xs_.swap(xs_try_);
  us_.swap(us_try_);
  data_at_solution_ = true;
  cost_ = cost + dT.cost;
  for (auto& f : fs_) f.setZero();
  gap_ = tail_gap_ = 0.0;
  feasible_ = true;
  return true;
}

double Solver::computeGaps() {
  const StateSpace& state = problem_.state();
  state.difference(xs_[0], problem_.x0(), fs_[0]);
  tail_gap_ = 0.0;
  for (int k = 0; k < T_; ++k) {
    state.difference(xs_[k + 1], problem_.data(k).x_next, fs_[k + 1]);
    tail_gap_ += fs_[k + 1].lpNorm<1>();
  }
  return fs_[0].lpNorm<1>() + tail_gap_;
}

void Solver::emulateSlowHost(Clock::time_point since) const {
  if (!(options.emulated_slowdown > 1.0)) return;
  const auto until = Clock::now() + (Clock::now() - since) * (options.emulated_slowdown - 1.0);
  while (Clock::now() < until) {
  }
}

bool Solver::computeDerivatives(Clock::time_point deadline) {
  derive_next_ = 0;
  return derivatives(deadline);
}

bool Solver::derivatives(Clock::time_point deadline) {
  cut_ = false;
  // In chunks of knots from derive_next_ (knot index T_: the terminal one), the deadline checked
  // between them; a cut one resumes there.
  const int chunk = kDeadlineKnots * problem_.threads();
  double cost = 0.0;
  while (derive_next_ <= T_) {
    const Clock::time_point start = Clock::now();
    const int end = std::min(derive_next_ + chunk, T_ + 1);
    cost = problem_.calcDiff(xs_, us_, derive_next_, end);  // the total over all knots
    emulateSlowHost(start);
    derive_next_ = end;
    if (derive_next_ <= T_ && Clock::now() >= deadline) {
      cut_ = true;
      return false;
    }
  }
  data_at_solution_ = true;  // every knot derived at xs_
  const SlowHostGuard slow{*this};
  const double gap = computeGaps();
  if (!std::isfinite(cost) || !std::isfinite(gap)) return false;
  cost_ = cost;
  gap_ = gap;
  feasible_ = gap_ < options.gap_tolerance;
  return true;
}

namespace {
// X <- X · blockdiag(J_b, I), J_b the leading 6 x 6 block (nb = 6) or nothing (nb = 0).
template <typename Derived>
void timesBlockRight(Eigen::MatrixBase<Derived>&& X, const Eigen::Matrix<double, 6, 6>& J, int nb,
                     Eigen::Matrix<double, Eigen::Dynamic, 6>& work) {
  if (nb == 0) return;
  auto w = work.topRows(X.rows());
  w.noalias() = X.template leftCols<6>() * J;
  X.template leftCols<6>() = w;
}
// X <- blockdiag(J_b, I)ᵀ · X.
template <typename Derived>
void transposeTimesBlockLeft(Eigen::MatrixBase<Derived>&& X, const Eigen::Matrix<double, 6, 6>& J,
                             int nb, Eigen::Matrix<double, 6, Eigen::Dynamic>& work) {
  if (nb == 0) return;
  auto w = work.leftCols(X.cols());
  w.noalias() = J.transpose() * X.template topRows<6>();
  X.template topRows<6>() = w;
}
}  // namespace

// Qxx, Qxu, Quu through the Euler structure (action.hpp): Fx = E + B G, Fu = B H with
// E = [Jq 0; 0 0], B = [dt Jv; I] and G, H the velocity rows of Fx, Fu (the knot's own results).
// With V the regularized next value Hessian, V Fx = [V_q Jq, 0] + (V B) G and
// Fxᵀ Y = [Jqᵀ Y_q; 0] + Gᵀ (Bᵀ Y), where products with Jq, Jv cost O(n²) (identities but for one
// 6 x 6 block) and only the products with G (nv x 2nv) and H (nv x nu) are dense: half the flops of
// Fxᵀ V Fx formed directly.
void Solver::eulerProducts(const ActionData& d, int nu) {
  const EulerStructure& e = d.euler;
  const int n = ndx_ / 2, nb = e.nb;  // nb: 0 or 6
  const double dt = e.dt;
  const Eigen::MatrixXd& V = Vxx_next_;
  const auto G = d.Fx.bottomRows(n);
  // VB = V B = dt V_q Jv + V_v (2n x n).
  auto VB = VB_.leftCols(n);
  VB = V.leftCols(n);
  timesBlockRight(VB.leftCols(n), e.Jv, nb, colwork_);
  VB = dt * VB + V.rightCols(n);
  // V Fx = [V_q Jq, 0] + VB G.
  VFx_.leftCols(n) = V.leftCols(n);
  timesBlockRight(VFx_.leftCols(n), e.Jq, nb, colwork_);
  VFx_.rightCols(n).setZero();
  VFx_.noalias() += VB * G;
  // Bᵀ V Fx = dt Jvᵀ (V Fx)_q + (V Fx)_v (n x 2n).
  auto BtVFx = BtY_.leftCols(ndx_);
  BtVFx = VFx_.topRows(n);
  transposeTimesBlockLeft(BtVFx.leftCols(ndx_), e.Jv, nb, rowwork_);
  BtVFx = dt * BtVFx + VFx_.bottomRows(n);
  // Qxx = Lxx + [Jqᵀ (V Fx)_q; 0] + Gᵀ Bᵀ V Fx.
  auto EtVFx = EtY_.leftCols(ndx_);
  EtVFx = VFx_.topRows(n);
  transposeTimesBlockLeft(EtVFx.leftCols(ndx_), e.Jq, nb, rowwork_);
  Qxx_ = d.Lxx;
  Qxx_.topRows(n) += EtVFx;
  // Qxx is symmetric: its lower triangle is the sum of its terms' lower triangles.
  Qxx_.triangularView<Eigen::Lower>() += G.transpose() * BtVFx;
  if (nu == 0) return;
  // V Fu = VB H; Qxu = Lxu + [Jqᵀ (V Fu)_q; 0] + Gᵀ Bᵀ V Fu; Quu = Luu + Hᵀ Bᵀ V Fu.
  const auto H = d.Fu.bottomRows(n);
  auto VFu = VFu_.leftCols(nu);
  VFu.noalias() = VB * H;
  auto BtVFu = BtY_.leftCols(nu);
  BtVFu = VFu.topRows(n);
  transposeTimesBlockLeft(BtVFu.leftCols(nu), e.Jv, nb, rowwork_);
  BtVFu = dt * BtVFu + VFu.bottomRows(n);
  auto EtVFu = EtY_.leftCols(nu);
  EtVFu = VFu.topRows(n);
  transposeTimesBlockLeft(EtVFu.leftCols(nu), e.Jq, nb, rowwork_);
  auto Qxu = Qxu_.leftCols(nu);
  Qxu = d.Lxu;
  Qxu.topRows(n) += EtVFu;
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
  SlowHostGuard slow{*this};  // its start moves to each deadline check: emulated per chunk
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
      emulateSlowHost(slow.start);
      slow.start = Clock::now();
      if (slow.start >= deadline) {  // Vx_next_, Vxx_next_ hold knot k + 1's value
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
        invertFromCholesky(qp.freeFactor(), nf, Quu_inv_);
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
        invertFromCholesky(Quu_, nu, Quu_inv_);
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

void Solver::predictChange() {
  // The step's first- and second-order cost change, d1 and d2, along the linearized rollout at
  // α = 1 (δx_0 = f_0, δu = k + K δx, δx⁺ = Fx δx + Fu δu + f): the cost's quadratic model at
  // step α then predicts α d1 + ½ α² d2, exact for linear dynamics and quadratic costs.
  d1_ = d2_ = 0.0;
  dx_ = fs_[0];
  for (int k = 0; k < T_; ++k) {
    const ActionData& d = problem_.data(k);
    const int nu = problem_.nu(k);
    auto du = du_.head(nu);
    du = k_[k];
    du.noalias() += K_[k] * dx_;
    d1_ += d.Lx.dot(dx_) + d.Lu.dot(du);
    tmp_x_.noalias() = d.Lxx * dx_;
    tmp_x_.noalias() += 2.0 * (d.Lxu * du);
    d2_ += dx_.dot(tmp_x_);
    w_.head(nu).noalias() = d.Luu * du;
    d2_ += du.dot(w_.head(nu));
    dx_next_ = fs_[k + 1];
    dx_next_.noalias() += d.Fx * dx_;
    dx_next_.noalias() += d.Fu * du;
    dx_.swap(dx_next_);
  }
  const ActionData& dT = problem_.terminalData();
  d1_ += dT.Lx.dot(dx_);
  tmp_x_.noalias() = dT.Lxx * dx_;
  d2_ += dx_.dot(tmp_x_);
}

double Solver::forwardPass(double alpha) {
  const SlowHostGuard slow{*this};
  ++forward_passes_;
  data_at_solution_ = false;  // the knots' data become the trial's (true again if accepted)
  const StateSpace& state = problem_.state();
  const bool box = kind_ == SolverKind::BoxFddp && has_bounds_;
  // x̂_0 = x_0 ⊕ α f_0, û = u + α k + K (x̂ ⊖ x), x̂⁺ = f(x̂, û) ⊕ (α - 1) f: the gaps shrink to
  // (1 - α) f (zero for a full step).
  tmp_x_ = alpha * fs_[0];
  state.integrate(xs_[0], tmp_x_, xs_try_[0]);
  double cost = 0.0;
  for (int k = 0; k < T_; ++k) {
    const int nu = problem_.nu(k);
    state.difference(xs_[k], xs_try_[k], dx_);
    Eigen::VectorXd& u = us_try_[k];
    u = us_[k] + alpha * k_[k];
    u.noalias() += K_[k] * dx_;
    if (box) u = u.cwiseMax(u_lower_.head(nu)).cwiseMin(u_upper_.head(nu));
    ActionData& d = problem_.data(k);
    problem_.knot(k).calc(d, xs_try_[k], u);
    if (d.status != KnotStatus::Ok) return kInfinity;
    cost += d.cost;
    if (feasible_) {
      xs_try_[k + 1] = d.x_next;
    } else {
      tmp_x_ = (alpha - 1.0) * fs_[k + 1];
      state.integrate(d.x_next, tmp_x_, xs_try_[k + 1]);
    }
  }
  ActionData& dT = problem_.terminalData();
  problem_.terminal().calc(dT, xs_try_[T_], Eigen::VectorXd());
  if (dT.status != KnotStatus::Ok) return kInfinity;
  cost += dT.cost;
  return std::isfinite(cost) ? cost : kInfinity;
}

bool Solver::prepare(Clock::time_point deadline, SolveStatus& status) {
  const Clock::time_point start = Clock::now();
  if (!preparing_) {  // a new preparation; else the one a deadline cut resumes where it stopped
    prepared_ = false;
    preparing_ = true;
    derived_ = false;
    derive_next_ = 0;
    backward_next_ = -1;
    backward_passes_ = 0;
    prepare_ms_ = 0.0;
  }
  const auto stop = [&](SolveStatus why) {
    prepare_ms_ += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (why != SolveStatus::Deadline) {
      preparing_ = false;
      why = fail(why);
    }
    status = why;
    return false;
  };
  if (start >= deadline) return stop(SolveStatus::Deadline);
  if (!derived_) {
    if (derive_next_ == 0 && !finiteTrajectory()) return stop(SolveStatus::NonFinite);
    if (!derivatives(deadline)) return stop(cut_ ? SolveStatus::Deadline : SolveStatus::NonFinite);
    derived_ = true;
  }
  // A Quu that is not positive definite: more regularization, until the limit or the deadline.
  // From μ = 0 the first raise goes to kRegFloor, so the retries are bounded.
  while (!backward(deadline)) {
    if (cut_) return stop(SolveStatus::Deadline);
    if (backward_nonfinite_) return stop(SolveStatus::NonFinite);
    reg_ = std::max(reg_ * options.reg_factor, kRegFloor);
    if (reg_ > options.reg_max) return stop(SolveStatus::NoDescent);
    if (Clock::now() >= deadline) {
      // The retry starts at the next call, with the raised μ.
      status = SolveStatus::Deadline;
      prepare_ms_ += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      return false;
    }
  }
  prepare_ms_ += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  preparing_ = false;
  prepared_ = true;
  return true;
}

SolveStatus Solver::solve(int max_iterations, Clock::time_point deadline) {
  iterations_ = 0;
  forward_passes_ = 0;
  if (!prepared_ && !preparing_) backward_passes_ = 0;  // else they count the preparation's
  if (kind_ == SolverKind::Ddp) {
    discardPreparation();  // the rollout from x0 moves the trajectory the preparation linearized
    if (!rollout()) return fail(SolveStatus::NonFinite);
  }
  if (!finiteTrajectory()) return fail(SolveStatus::NonFinite);
  for (int it = 0; it < max_iterations; ++it) {
    SolveStatus status = SolveStatus::MaxIterations;
    if (!prepared_ && !prepare(deadline, status)) return status;
    const Clock::time_point start = Clock::now();
    if (start >= deadline) return SolveStatus::Deadline;  // the preparation stays for the next
    // The preparation is used once: the step below moves the trajectory it linearized.
    prepared_ = false;
    IterationStats s;
    s.iteration = it;
    // x0 enters here and only here: the gap f_0 (the backward pass reads f_1 ... f_T), and with
    // it the feasibility and the predicted change of the step.
    problem_.state().difference(xs_[0], problem_.x0(), fs_[0]);
    gap_ = fs_[0].lpNorm<1>() + tail_gap_;
    feasible_ = gap_ < options.gap_tolerance;
    predictChange();
    s.stop = std::abs(d1_);
    const bool converged = s.stop < options.stop_tolerance && feasible_;
    double alpha = 1.0;
    bool accepted = false, out_of_time = false;
    Clock::duration trial{0};  // the last trial's duration: the next one's expected
    for (int i = 0; !converged && i < options.line_search_steps; ++i, alpha *= 0.5) {
      // A trial that would end after the deadline is not started: the answer stays on time.
      const Clock::time_point trial_start = Clock::now();
      if (trial_start + trial >= deadline) {
        out_of_time = true;
        break;
      }
      const double cost_try = forwardPass(alpha);
      trial = Clock::now() - trial_start;
      const double expected = expectedCostChange(alpha);
      const double actual = cost_try - cost_;
      // A predicted decrease must be realized at least in part (Armijo-like); closing gaps may
      // raise the cost, by at most twice the prediction.
      const double slack = 1e-12 * std::max(1.0, std::abs(cost_));
      const bool ok = std::isfinite(cost_try) &&
                      (expected < 0.0 ? actual <= options.accept_ratio * expected + slack
                                      : actual <= 2.0 * expected + slack);
      if (ok) {
        accepted = true;
        xs_.swap(xs_try_);
        us_.swap(us_try_);
        data_at_solution_ = true;
        s.expected = expected;
        s.actual = actual;
        cost_ = cost_try;
        if (!feasible_) {
          for (auto& f : fs_) f *= (1.0 - alpha);
          gap_ *= (1.0 - alpha);
          feasible_ = alpha == 1.0 || gap_ < options.gap_tolerance;
        }
        break;
      }
    }
    // μ adapts to the step taken; a line search cut short by the deadline says nothing about μ.
    if (accepted) {
      if (alpha >= options.step_decrease_reg)
        reg_ = std::max(reg_ / options.reg_factor, options.reg_min);
      else if (alpha <= options.step_increase_reg)
        reg_ = std::min(reg_ * options.reg_factor, options.reg_max);
    } else if (!converged && !out_of_time) {
      reg_ = std::max(reg_ * options.reg_factor, kRegFloor);
    }
    s.step = accepted ? alpha : 0.0;
    s.cost = cost_;
    s.gap = gap_;
    s.regularization = reg_;
    s.time_ms =
        prepare_ms_ + std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (iterations_ < kMaxStats) stats_[iterations_] = s;
    ++iterations_;
    if (callback) callback(s);
    if (converged) return SolveStatus::Converged;
    if (out_of_time || Clock::now() >= deadline) return SolveStatus::Deadline;
    if (!accepted && reg_ > options.reg_max) return fail(SolveStatus::NoDescent);
  }
  return SolveStatus::MaxIterations;
}

// After a failure μ starts again from its initial value: it carries over between solves, and a
// stuck 1e9 would cripple the next ones.
SolveStatus Solver::fail(SolveStatus status) {
  reg_ = options.reg_initial;
  return status;
}

void Solver::printIterationTable(const IterationStats& s) {
  if (s.iteration % 10 == 0)
    std::printf("%5s %14s %11s %11s %11s %9s %9s %9s\n", "iter", "cost", "gap", "stop", "expected",
                "step", "reg", "ms");
  std::printf("%5d %14.8e %11.3e %11.3e %11.3e %9.4f %9.1e %9.3f\n", s.iteration, s.cost, s.gap,
              s.stop, s.expected, s.step, s.regularization, s.time_ms);
}

}  // namespace stride
