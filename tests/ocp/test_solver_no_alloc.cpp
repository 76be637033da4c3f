// The solver's loop does not touch the heap: Solver::solve (FDDP and box-FDDP, one thread and
// two: SolverNoAllocationOpenMP; Euler and RK4 knots), ShootingProblem::shift,
// Solver::shiftWarmStart and the in-place re-configuration of a knot (mode, contacts, terms,
// references), on the solver's own fixture (shooting_cases.hpp: knots with different contact
// sets, impulse knots, friction cones, swing feet; nothing of locomotion/). The locomotion
// problem's own tick (its update, the gait generator, a solve of its trot) is checked in
// tests/locomotion/test_locomotion_no_alloc.cpp. As in tests/ocp/test_ocp_no_alloc.cpp, malloc
// and its relatives are interposed and counted (operator new and Eigen both end there), with
// Eigen's own check (EIGEN_RUNTIME_NO_MALLOC) armed as well; the interposition is per binary,
// hence this separate executable.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "ocp/shooting_cases.hpp"
#include "solver/ddp/solver.hpp"

namespace stride {
namespace test_solver_no_alloc {

using test_support::AllocationCounter;
using test_support::allocations;

TEST(SolverNoAllocation, CounterSeesAllocations) {
  EXPECT_GE(allocations([] {
              Eigen::internal::set_is_malloc_allowed(true);
              std::vector<int> v(10);
              int* volatile data = v.data();  // volatile: clang may drop an unused allocation
              (void)data;
            }),
            1);
}

std::unique_ptr<shooting_cases::Steps> steps(Integrator integrator = Integrator::Euler) {
  return shooting_cases::solo12Steps(STRIDE_SHARED_DIR, integrator);
}

// The allocations of `iterations` solves from the standing warm start (its copy included), after
// one warm-up solve (the first parallel region creates OpenMP's thread pool; the first solve
// sizes nothing else).
long warmSolveAllocations(Solver& solver, const shooting_cases::Steps& p, int iterations) {
  EXPECT_TRUE(solver.setWarmStart(p.xs, p.us));
  solver.solve(1);
  return allocations([&] {
    solver.setWarmStart(p.xs, p.us);
    solver.solve(iterations);
  });
}

void solveNoAllocation(int threads, Integrator integrator = Integrator::Euler) {
  auto p = steps(integrator);
  p->problem->setThreads(threads);
  for (SolverKind kind : {SolverKind::Fddp, SolverKind::BoxFddp}) {
    Solver solver(*p->problem, kind);
    if (kind == SolverKind::BoxFddp) {
      const int nu = p->problem->maxNu();
      solver.setControlBounds(Eigen::VectorXd::Constant(nu, -1.0),
                              Eigen::VectorXd::Constant(nu, 1.0));
    }
    const long n = warmSolveAllocations(solver, *p, 5);
    EXPECT_GT(solver.iterations(), 0);
    EXPECT_EQ(n, 0) << (kind == SolverKind::Fddp ? "Fddp, " : "BoxFddp, ") << threads
                    << " thread(s)";
  }
}

TEST(SolverNoAllocation, Solve) {
  solveNoAllocation(1);
}

// Every contact knot by RK4 (the impulse knots as they are): the stages' workspaces are made at
// setup, and the solver takes the general (not Euler-structured) Riccati products.
TEST(SolverNoAllocation, SolveWithRk4Knots) {
  solveNoAllocation(1, Integrator::Rk4);
}

// With OpenMP's threads: gcc's libgomp allocates nothing once its pool exists, clang's libomp
// allocates in every parallel region: label openmp_alloc (tests/CMakeLists.txt), left out of
// tools/test.sh --sanitize (tests/README.md, "Sanitizers").
TEST(SolverNoAllocationOpenMP, SolveWithTwoThreads) {
  solveNoAllocation(2);
}

TEST(SolverNoAllocationOpenMP, SolveWithTwoThreadsRk4Knots) {
  solveNoAllocation(2, Integrator::Rk4);
}

// Box-FDDP with a single free control per knot (every other one pinned at a bound): the feedback
// gains come from a 1 x 1 free block, a row-vector product in Eigen.
TEST(SolverNoAllocation, BoxFddpWithOneFreeControl) {
  auto p = steps();
  Solver solver(*p->problem, SolverKind::BoxFddp);
  const int nu = p->problem->maxNu();
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::VectorXd lower = Eigen::VectorXd::Constant(nu, 1e-3), upper = lower;
  lower[0] = -inf;
  upper[0] = inf;
  solver.setControlBounds(lower, upper);
  const long n = warmSolveAllocations(solver, *p, 3);
  EXPECT_GT(solver.backwardPasses(), 0);
  EXPECT_EQ(n, 0);
}

// What a receding horizon does every tick, with the solver's types alone: shift the knots and the
// warm start by one, then re-configure the knot that came in at the end, in place, for the phase
// it now stands for (its mode, contacts, which terms are on, their weights and references), and
// iterate once.
TEST(SolverNoAllocation, ShiftAndReconfigureInPlace) {
  auto p = steps();
  ShootingProblem& problem = *p->problem;
  Solver solver(problem, SolverKind::Fddp);
  ASSERT_TRUE(solver.setWarmStart(p->xs, p->us));
  solver.solve(1);
  const int T = problem.horizon(), nc = p->contacts.size();
  Eigen::VectorXd u_ref(p->us[0].size());
  Eigen::Vector3d foot;
  for (int tick = 0; tick < 80; ++tick) {
    const long n = allocations([&] {
      problem.shift(1);
      solver.shiftWarmStart(1);
      // The knot that stood for knot `tick` now stands for knot T + tick: the phases repeat with
      // the fixture's period of T knots.
      bool touchdown = false;
      const unsigned mask = shooting_cases::closedAt(tick % T, touchdown);
      auto& knot = static_cast<KnotModel&>(problem.knot(T - 1));
      knot.setMode(touchdown ? KnotMode::Impulse : KnotMode::Contact);
      CostModel& costs = knot.costs();
      for (int c = 0; c < nc; ++c) {
        const bool closed = (mask >> c) & 1u;
        knot.contacts().setActive(c, closed);
        CostTerm& cone = costs[shooting_cases::coneTerm(c)];
        cone.active = closed;
        static_cast<FrictionConeResidual&>(*cone.residual)
            .setMinimumNormalForce(touchdown ? 0.0 : shooting_cases::kMinNormalForce);
        CostTerm& swing = costs[shooting_cases::swingTerm(c)];
        swing.active = !closed || touchdown;
        foot = static_cast<FrameTranslationResidual&>(*swing.residual).reference();
        foot.z() = 0.01 * (tick % 5);
        static_cast<FrameTranslationResidual&>(*swing.residual).setReference(foot);
      }
      u_ref.setConstant(0.01 * tick);
      static_cast<ControlResidual&>(*costs[shooting_cases::kControlTerm].residual)
          .setReference(u_ref);
      solver.solve(1);
    });
    EXPECT_EQ(n, 0) << "tick " << tick;
  }
  EXPECT_GT(solver.iterations(), 0);
}

}  // namespace test_solver_no_alloc
}  // namespace stride
