// The DDP solvers on a linear-quadratic problem, where one iteration must land exactly on the
// solution of the dense KKT system of the same problem, and the quadratic model of the step must
// predict the actual cost change.

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "controller/slow_host.hpp"
#include "ocp/lq_action.hpp"
#include "solver/ddp/solver.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/urdf.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"

namespace stride {
namespace test_solver {

using test_support::LqKnot;

struct LqProblem {
  std::vector<const LqKnot*> knots;  // T running + terminal
  std::unique_ptr<ShootingProblem> problem;
  int nx, nu, T;
};

LqProblem makeLq(int nx, int nu, int T, unsigned seed) {
  std::mt19937 rng(seed);
  LqProblem p{{}, nullptr, nx, nu, T};
  std::vector<std::unique_ptr<ActionModel>> running;
  for (int k = 0; k < T; ++k) {
    auto m = LqKnot::random(nx, nu, false, rng);
    p.knots.push_back(m.get());
    running.push_back(std::move(m));
  }
  auto terminal = LqKnot::random(nx, nu, true, rng);
  p.knots.push_back(terminal.get());
  Eigen::VectorXd x0 = Eigen::VectorXd::Random(nx);
  p.problem = std::make_unique<ShootingProblem>(x0, std::move(running), std::move(terminal));
  return p;
}

// The solution (xs, us) of the LQ problem from its dense KKT system.
void denseSolution(const LqProblem& p, std::vector<Eigen::VectorXd>& xs,
                   std::vector<Eigen::VectorXd>& us) {
  const int nx = p.nx, nu = p.nu, T = p.T;
  const int nz = nx * (T + 1) + nu * T, nc = nx * (T + 1);
  auto xi = [&](int k) { return nx * k; };
  auto ui = [&](int k) { return nx * (T + 1) + nu * k; };
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(nz, nz), C = Eigen::MatrixXd::Zero(nc, nz);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(nz), d = Eigen::VectorXd::Zero(nc);
  for (int k = 0; k <= T; ++k) {
    const LqKnot& m = *p.knots[k];
    H.block(xi(k), xi(k), nx, nx) = m.Q;
    h.segment(xi(k), nx) = m.q;
    if (k < T) {
      H.block(ui(k), ui(k), nu, nu) = m.R;
      H.block(xi(k), ui(k), nx, nu) = m.N;
      H.block(ui(k), xi(k), nu, nx) = m.N.transpose();
      h.segment(ui(k), nu) = m.r;
      // x_{k+1} - A x_k - B u_k = c
      C.block(nx * (k + 1), xi(k + 1), nx, nx).setIdentity();
      C.block(nx * (k + 1), xi(k), nx, nx) = -m.A;
      C.block(nx * (k + 1), ui(k), nx, nu) = -m.B;
      d.segment(nx * (k + 1), nx) = m.c;
    }
  }
  C.block(0, 0, nx, nx).setIdentity();
  d.head(nx) = p.problem->x0();
  Eigen::MatrixXd KKT = Eigen::MatrixXd::Zero(nz + nc, nz + nc);
  KKT.topLeftCorner(nz, nz) = H;
  KKT.topRightCorner(nz, nc) = C.transpose();
  KKT.bottomLeftCorner(nc, nz) = C;
  Eigen::VectorXd rhs(nz + nc);
  rhs << -h, d;
  const Eigen::VectorXd z = KKT.fullPivLu().solve(rhs);
  xs.assign(T + 1, Eigen::VectorXd());
  us.assign(T, Eigen::VectorXd());
  for (int k = 0; k <= T; ++k) xs[k] = z.segment(xi(k), nx);
  for (int k = 0; k < T; ++k) us[k] = z.segment(ui(k), nu);
}

double maxDifference(const std::vector<Eigen::VectorXd>& a, const std::vector<Eigen::VectorXd>& b) {
  double e = 0.0;
  for (size_t k = 0; k < a.size(); ++k) e = std::max(e, (a[k] - b[k]).cwiseAbs().maxCoeff());
  return e;
}

class LqExact : public ::testing::TestWithParam<SolverKind> {};

TEST_P(LqExact, OneIterationReachesTheKktSolution) {
  for (unsigned seed : {1u, 2u, 3u}) {
    LqProblem p = makeLq(6, 3, 20, seed);
    std::vector<Eigen::VectorXd> xs_ref, us_ref;
    denseSolution(p, xs_ref, us_ref);
    Solver solver(*p.problem, GetParam());
    solver.options.reg_min = 0.0;
    solver.setRegularization(0.0);
    // An infeasible warm start (random states, gaps everywhere), except for Ddp which rolls out.
    std::vector<Eigen::VectorXd> xs(p.T + 1), us(p.T);
    std::mt19937 rng(seed + 100);
    std::normal_distribution<double> n(0.0, 1.0);
    for (auto& x : xs) x = Eigen::VectorXd::NullaryExpr(p.nx, [&] { return n(rng); });
    for (auto& u : us) u = Eigen::VectorXd::NullaryExpr(p.nu, [&] { return n(rng); });
    ASSERT_TRUE(solver.setWarmStart(xs, us));
    solver.solve(1);
    ASSERT_EQ(solver.iterations(), 1);
    const IterationStats& s = solver.stats()[0];
    EXPECT_EQ(s.step, 1.0);
    EXPECT_LT(maxDifference(solver.xs(), xs_ref), 1e-9);
    EXPECT_LT(maxDifference(solver.us(), us_ref), 1e-9);
    EXPECT_LT(solver.gap(), 1e-12);
    // The quadratic model is exact for an LQ problem.
    EXPECT_NEAR(s.expected, s.actual, 1e-9 * std::max(1.0, std::abs(s.actual)));
    // The next iteration finds nothing left to do.
    EXPECT_EQ(solver.solve(5), SolveStatus::Converged);
    EXPECT_EQ(solver.iterations(), 1);
  }
}

INSTANTIATE_TEST_SUITE_P(Solvers, LqExact,
                         ::testing::Values(SolverKind::Ddp, SolverKind::Fddp, SolverKind::BoxFddp),
                         [](const auto& info) {
                           return std::string(info.param == SolverKind::Ddp    ? "Ddp"
                                              : info.param == SolverKind::Fddp ? "Fddp"
                                                                               : "BoxFddp");
                         });

// The quadratic model predicts the cost change of any step length on an LQ problem, gaps and all.
TEST(Fddp, ExpectedChangeMatchesActualForEveryStep) {
  LqProblem p = makeLq(5, 2, 15, 7);
  Solver solver(*p.problem, SolverKind::Fddp);
  solver.setRegularization(0.0);
  std::vector<Eigen::VectorXd> xs(p.T + 1, Eigen::VectorXd::Ones(p.nx)),
      us(p.T, Eigen::VectorXd::Ones(p.nu));
  ASSERT_TRUE(solver.setWarmStart(xs, us));
  ASSERT_TRUE(solver.computeDerivatives());
  const double cost = solver.cost();
  ASSERT_GT(solver.gap(), 1.0);
  ASSERT_TRUE(solver.backwardPass());
  solver.predictChange();
  for (double alpha : {1.0, 0.5, 0.25, 0.125, 0.01}) {
    const double change = solver.forwardPass(alpha) - cost;
    EXPECT_NEAR(solver.expectedCostChange(alpha), change, 1e-9 * std::abs(cost)) << alpha;
  }
}

// The box QP on random strictly convex problems: the KKT conditions of its solution (zero
// gradient on the free variables, the gradient pushing outwards on the clamped ones), for boxes
// that hold the unconstrained minimizer (its fast path: x = -H^-1 g, all free) and boxes that cut
// it; and its factor of the free block, which the solver inverts for the gains.
TEST(BoxQP, SolutionSatisfiesKktConditions) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const int n = 7;
  BoxQP qp(n);
  int inside = 0, cut = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::MatrixXd A(n, n);
    for (int i = 0; i < A.size(); ++i) A.data()[i] = U(rng);
    const Eigen::MatrixXd H = A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd g(n), lb(n), ub(n), x = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i) g[i] = 3.0 * U(rng);
    const Eigen::VectorXd x_free = -H.llt().solve(g);
    const double width = trial % 2 ? 2.0 * x_free.cwiseAbs().maxCoeff() : 0.5;
    for (int i = 0; i < n; ++i) {
      lb[i] = -width * (1.0 + 0.5 * U(rng));
      ub[i] = width * (1.0 + 0.5 * U(rng));
    }
    const bool holds = (x_free.array() >= lb.array()).all() && (x_free.array() <= ub.array()).all();
    ASSERT_TRUE(qp.solve(H, g, lb, ub, x));
    const Eigen::VectorXd grad = H * x + g;
    EXPECT_TRUE((x.array() >= lb.array()).all() && (x.array() <= ub.array()).all());
    const Eigen::VectorXi& F = qp.freeIndices();
    std::vector<bool> is_free(n, false);
    for (int a = 0; a < qp.nfree(); ++a) is_free[F[a]] = true;
    for (int i = 0; i < n; ++i) {
      if (is_free[i]) {
        EXPECT_NEAR(grad[i], 0.0, 1e-8) << "trial " << trial << " free " << i;
      } else {
        EXPECT_TRUE((x[i] == lb[i] && grad[i] > 0.0) || (x[i] == ub[i] && grad[i] < 0.0))
            << "trial " << trial << " clamped " << i;
      }
    }
    if (holds) {
      ++inside;
      EXPECT_EQ(qp.nfree(), n);
      EXPECT_LT((x - x_free).cwiseAbs().maxCoeff(), 1e-10 * std::max(1.0, x_free.norm()));
    } else {
      ++cut;
    }
    // The factor of the free block: L Lᵀ = H_FF.
    const int nf = qp.nfree();
    if (nf == 0) continue;
    Eigen::MatrixXd Hff(nf, nf);
    for (int a = 0; a < nf; ++a)
      for (int b = 0; b < nf; ++b) Hff(a, b) = H(F[a], F[b]);
    const Eigen::MatrixXd L = qp.freeFactor().topLeftCorner(nf, nf).triangularView<Eigen::Lower>();
    EXPECT_LT((L * L.transpose() - Hff).cwiseAbs().maxCoeff(), 1e-10 * std::max(1.0, Hff.norm()));
  }
  EXPECT_GT(inside, 50);
  EXPECT_GT(cut, 50);
}

// Box-FDDP keeps every control within its bounds and, with bounds that are never reached, gives
// the unconstrained solution.
TEST(BoxFddp, RespectsBoundsAndMatchesFddpWhenInactive) {
  LqProblem p = makeLq(6, 3, 20, 11);
  std::vector<Eigen::VectorXd> xs_ref, us_ref;
  denseSolution(p, xs_ref, us_ref);
  double umax = 0.0;
  for (const auto& u : us_ref) umax = std::max(umax, u.cwiseAbs().maxCoeff());
  {
    Solver solver(*p.problem, SolverKind::BoxFddp);
    solver.setControlBounds(Eigen::VectorXd::Constant(3, -2 * umax),
                            Eigen::VectorXd::Constant(3, 2 * umax));
    solver.solve(10);
    EXPECT_LT(maxDifference(solver.us(), us_ref), 1e-7);
  }
  Solver solver(*p.problem, SolverKind::BoxFddp);
  const double bound = 0.5 * umax;
  solver.setControlBounds(Eigen::VectorXd::Constant(3, -bound),
                          Eigen::VectorXd::Constant(3, bound));
  const SolveStatus status = solver.solve(50);
  EXPECT_EQ(status, SolveStatus::Converged) << toString(status);
  for (const auto& u : solver.us()) EXPECT_LE(u.cwiseAbs().maxCoeff(), bound + 1e-12);
  // The box solution is optimal among feasible controls: no worse than clamping the unconstrained
  // optimum, and strictly more expensive than the unconstrained optimum.
  Solver clamped(*p.problem, SolverKind::Ddp);
  std::vector<Eigen::VectorXd> us_clamped = us_ref;
  for (auto& u : us_clamped) u = u.cwiseMax(-bound).cwiseMin(bound);
  ASSERT_TRUE(clamped.setWarmStart(xs_ref, us_clamped));
  clamped.solve(0);  // Ddp rolls the controls out from x0: the cost of the clamped optimum
  const double clamped_cost = clamped.cost();
  EXPECT_LE(solver.cost(), clamped_cost + 1e-9);
}

// The Riccati products through the Euler structure of the contact knots equal the dense ones (the
// structured route runs for nv >= 24: talos here; solo12 checks the dense route against itself).
TEST(Solver, EulerStructureMatchesDenseProducts) {
  for (const char* robot : {"solo12/solo12.urdf", "talos/talos_reduced.urdf"}) {
    const Model model = buildModelFromUrdf(std::string(STRIDE_SHARED_DIR) + "/robots/" + robot,
                                           RootJoint::FreeFlyer);
    const bool solo = std::string(robot).find("solo") != std::string::npos;
    ContactSet contacts;
    if (solo) {
      for (const char* f : {"FL_FOOT", "HR_FOOT"})
        contacts.add(model, f, 3, ReferenceFrame::LocalWorldAligned, 0.0, 50.0);
    } else {
      contacts.add(model, "left_sole_link", 6, ReferenceFrame::LocalWorldAligned, 0.0, 50.0);
    }
    const int nu = model.nv - 6, T = 8;
    std::mt19937 rng(5);
    std::vector<Eigen::VectorXd> xs(T + 1), us(T);
    for (auto& x : xs) {
      x = Eigen::VectorXd::Zero(model.nq + model.nv);
      x.head(model.nq) = randomConfiguration(model, rng);
      x.tail(model.nv).setRandom();
    }
    for (auto& u : us) u = Eigen::VectorXd::Random(nu);
    std::vector<std::unique_ptr<ActionModel>> running;
    for (int k = 0; k < T; ++k) {
      auto knot = std::make_unique<KnotModel>(model, contacts, 0.01);
      knot->costs().add("state", std::make_unique<StateResidual>(model, nu),
                        Activation::quadratic(2 * model.nv), 1e-2);
      knot->costs().add("control", std::make_unique<ControlResidual>(model, nu),
                        Activation::quadratic(nu), 1e-3);
      running.push_back(std::move(knot));
    }
    auto terminal = std::make_unique<TerminalModel>(model);
    terminal->costs().add(
        "hand",
        std::make_unique<FrameTranslationResidual>(model, 0, solo ? "FR_FOOT" : "arm_right_7_link"),
        Activation::quadratic(3), 10.0);
    ShootingProblem problem(xs[0], std::move(running), std::move(terminal));
    Solver structured(problem), dense(problem);
    dense.options.exploit_structure = false;
    for (Solver* s : {&structured, &dense}) {
      ASSERT_TRUE(s->setWarmStart(xs, us));
      s->setRegularization(1e-6);
      ASSERT_TRUE(s->computeDerivatives());
      ASSERT_TRUE(s->backwardPass());
      s->predictChange();
    }
    for (int k = 0; k < T; ++k) {
      const double scale = 1.0 + dense.K()[k].cwiseAbs().maxCoeff();
      EXPECT_LT((structured.K()[k] - dense.K()[k]).cwiseAbs().maxCoeff(), 1e-9 * scale) << k;
      EXPECT_LT((structured.k()[k] - dense.k()[k]).cwiseAbs().maxCoeff(),
                1e-9 * (1.0 + dense.k()[k].cwiseAbs().maxCoeff()))
          << k;
    }
    EXPECT_NEAR(structured.expectedCostChange(1.0), dense.expectedCostChange(1.0),
                1e-9 * std::abs(dense.expectedCostChange(1.0)));
  }
}

// A non-finite value in a knot stops the solve with a status; the iterate stays the last good one.
TEST(Solver, NonFiniteKnotStopsWithStatus) {
  LqProblem p = makeLq(4, 2, 6, 9);
  for (SolverKind kind : {SolverKind::Ddp, SolverKind::Fddp, SolverKind::BoxFddp}) {
    Solver solver(*p.problem, kind);
    ASSERT_EQ(solver.solve(3), SolveStatus::Converged);
    const auto xs = solver.xs();
    const_cast<LqKnot*>(p.knots[3])->q[0] = std::nan("");
    EXPECT_EQ(solver.solve(3), SolveStatus::NonFinite);
    EXPECT_EQ(maxDifference(solver.xs(), xs), 0.0);
    const_cast<LqKnot*>(p.knots[3])->q[0] = 0.5;
  }
}

// A Quu that is not positive definite from μ = 0: the regularization rises (bounded retries) and
// the solve returns, converged once μ makes the step a descent.
TEST(Solver, IndefiniteQuuFromZeroRegularizationTerminates) {
  LqProblem p = makeLq(4, 2, 6, 13);
  const_cast<LqKnot*>(p.knots[2])->R = -50.0 * Eigen::MatrixXd::Identity(2, 2);
  Solver solver(*p.problem, SolverKind::Fddp);
  solver.setRegularization(0.0);
  const SolveStatus status =
      solver.solve(50, Solver::Clock::now() + std::chrono::milliseconds(200));
  EXPECT_NE(status, SolveStatus::Deadline) << toString(status);
  EXPECT_GT(solver.iterations() + (status == SolveStatus::NoDescent), 0);
}

// Non-finite derivatives (a finite value, a NaN in Fx) are NonFinite, not a regularization
// problem; μ restarts from its initial value.
TEST(Solver, NonFiniteDerivativesAreReportedAsSuch) {
  struct PoisonedKnot : LqKnot {
    using LqKnot::LqKnot;
    void calcDiff(ActionData& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                  const Eigen::Ref<const Eigen::VectorXd>& u) const override {
      LqKnot::calcDiff(d, x, u);
      d.Fx(0, 0) = std::nan("");
    }
  };
  std::mt19937 rng(3);
  std::vector<std::unique_ptr<ActionModel>> running;
  for (int k = 0; k < 4; ++k) {
    auto m = LqKnot::random(3, 2, false, rng);
    if (k == 1) {
      auto poisoned = std::make_unique<PoisonedKnot>(3, 2, false);
      poisoned->A = m->A, poisoned->B = m->B, poisoned->c = m->c, poisoned->Q = m->Q;
      poisoned->R = m->R, poisoned->N = m->N, poisoned->q = m->q, poisoned->r = m->r;
      running.push_back(std::move(poisoned));
    } else {
      running.push_back(std::move(m));
    }
  }
  ShootingProblem problem(Eigen::VectorXd::Ones(3), std::move(running),
                          LqKnot::random(3, 2, true, rng));
  Solver solver(problem, SolverKind::Fddp);
  solver.setRegularization(1e-3);
  EXPECT_EQ(solver.solve(5), SolveStatus::NonFinite);
  EXPECT_EQ(solver.regularization(), solver.options.reg_initial);
  for (const auto& x : solver.xs()) EXPECT_TRUE(x.allFinite());
}

// Knots with different control sizes: BoxFddp with bounds that never bind equals Fddp.
TEST(BoxFddp, KnotsWithDifferentControlSizes) {
  auto build = [&](unsigned seed) {
    std::mt19937 r(seed);
    std::vector<std::unique_ptr<ActionModel>> running;
    for (int k = 0; k < 8; ++k) running.push_back(LqKnot::random(4, k % 2 ? 2 : 3, false, r));
    return std::make_unique<ShootingProblem>(Eigen::VectorXd::Ones(4), std::move(running),
                                             LqKnot::random(4, 3, true, r));
  };
  auto p1 = build(4), p2 = build(4);
  Solver fddp(*p1, SolverKind::Fddp), box(*p2, SolverKind::BoxFddp);
  box.setControlBounds(Eigen::VectorXd::Constant(3, -1e6), Eigen::VectorXd::Constant(3, 1e6));
  EXPECT_EQ(fddp.solve(10), SolveStatus::Converged);
  EXPECT_EQ(box.solve(10), SolveStatus::Converged);
  EXPECT_LT(maxDifference(fddp.us(), box.us()), 1e-9);
}

// shiftWarmStart by n moves the trajectory n knots forward and repeats the last state and control
// in the tail, also for n = T.
TEST(Solver, ShiftWarmStartRepeatsTheTail) {
  LqProblem p = makeLq(3, 2, 5, 17);
  Solver solver(*p.problem, SolverKind::Ddp);
  solver.solve(3);
  const auto xs = solver.xs();
  const auto us = solver.us();
  solver.shiftWarmStart(2);
  EXPECT_EQ(solver.xs()[0], xs[2]);
  EXPECT_EQ(solver.xs()[3], xs[5]);
  EXPECT_EQ(solver.xs()[5], xs[5]);
  EXPECT_EQ(solver.us()[2], us[4]);
  EXPECT_EQ(solver.us()[4], us[4]);
  solver.shiftWarmStart(5);
  for (const auto& x : solver.xs()) EXPECT_EQ(x, xs[5]);
  for (const auto& u : solver.us()) EXPECT_EQ(u, us[4]);
}

TEST(Solver, DeadlineInThePastReturnsAtOnce) {
  LqProblem p = makeLq(4, 2, 6, 9);
  Solver solver(*p.problem);
  EXPECT_EQ(solver.solve(10, Solver::Clock::now() - std::chrono::milliseconds(1)),
            SolveStatus::Deadline);
  EXPECT_EQ(solver.iterations(), 0);
}

// A preparation cut by its deadline resumes where it stopped, and ends with exactly the gains of
// one made in one go. Every call below, on a host emulated 1000x slower, gets 1 ms: it does one
// chunk of knots (derivatives, then the backward pass) and stops at the check after it.
TEST(Solver, PreparationCutByItsDeadlineResumesExactly) {
  LqProblem a = makeLq(6, 3, 40, 21), b = makeLq(6, 3, 40, 21);
  b.problem->setX0(a.problem->x0());  // (drawn from Eigen's global generator: not the seed)
  Solver whole(*a.problem), cut(*b.problem);
  SolveStatus status = SolveStatus::MaxIterations;
  ASSERT_TRUE(whole.prepare(Solver::Clock::time_point::max(), status));
  SlowHost slow_host(1000.0);
  cut.options.work_hook = &slow_host;
  int calls = 0;
  bool done = false;
  while (!done && calls < 100) {
    done = cut.prepare(Solver::Clock::now() + std::chrono::milliseconds(1), status);
    ++calls;
    if (!done) {
      ASSERT_EQ(status, SolveStatus::Deadline);
      EXPECT_TRUE(cut.preparing());
    }
  }
  ASSERT_TRUE(done);
  EXPECT_FALSE(cut.preparing());
  // 41 knots of derivatives and 40 of backward pass in chunks of 8: 6 + 5 pieces.
  EXPECT_GE(calls, 10);
  EXPECT_EQ(cut.backwardPasses(), 1);
  for (int k = 0; k < a.T; ++k) {
    EXPECT_EQ(cut.K()[k], whole.K()[k]) << "knot " << k;
    EXPECT_EQ(cut.k()[k], whole.k()[k]) << "knot " << k;
  }
  // A discarded one starts again from its first knot.
  cut.options.work_hook = nullptr;
  ASSERT_FALSE(cut.prepare(Solver::Clock::now(), status));  // the deadline passed: nothing done
  EXPECT_TRUE(cut.preparing());
  cut.discardPreparation();
  EXPECT_FALSE(cut.preparing());
  EXPECT_FALSE(cut.prepared());
}

TEST(Solver, WarmStartRejectsBadSizesAndNaN) {
  LqProblem p = makeLq(4, 2, 5, 3);
  Solver solver(*p.problem);
  std::vector<Eigen::VectorXd> xs(p.T + 1, Eigen::VectorXd::Zero(4)),
      us(p.T, Eigen::VectorXd::Zero(2));
  EXPECT_TRUE(solver.setWarmStart(xs, us));
  xs[2][1] = std::nan("");
  EXPECT_FALSE(solver.setWarmStart(xs, us));
  xs[2][1] = 0.0;
  us.pop_back();
  EXPECT_FALSE(solver.setWarmStart(xs, us));
  EXPECT_THROW(solver.setControlBounds(Eigen::VectorXd::Ones(2), Eigen::VectorXd::Zero(2)),
               std::invalid_argument);
}

}  // namespace test_solver
}  // namespace stride
