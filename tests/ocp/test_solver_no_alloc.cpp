// The controller's tick does not touch the heap: Solver::solve (FDDP and box-FDDP, one thread and
// two), LocomotionProblem::update, ShootingProblem::shift and Solver::shiftWarmStart, on the
// solo12 trot. As in tests/ocp/test_ocp_no_alloc.cpp, malloc and its relatives are interposed and
// counted (operator new and Eigen both end there), with Eigen's own check
// (EIGEN_RUNTIME_NO_MALLOC) armed as well; the interposition is per binary, hence this separate
// executable.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <atomic>
#include <cstdlib>

#include "ocp/locomotion_cases.hpp"
#include "solver/ddp/solver.hpp"

namespace stride {
namespace {

using testing::AllocationCounter;
using testing::allocations;

TEST(SolverNoAllocation, CounterSeesAllocations) {
  EXPECT_GE(allocations([] {
              Eigen::internal::set_is_malloc_allowed(true);
              std::vector<int> v(10);
              (void)v;
            }),
            1);
}

struct Trot {
  loco_cases::Case c = loco_cases::make(loco_cases::Problem::SoloTrot, STRIDE_SHARED_DIR);
  std::vector<Eigen::VectorXd> xs, us;
  Trot() { c.warmStart(xs, us); }
};

// A few iterations of each solver from the standing warm start (the warm start's copy included).
TEST(SolverNoAllocation, Solve) {
  Trot trot;
  for (SolverKind kind : {SolverKind::Fddp, SolverKind::BoxFddp}) {
    Solver solver(trot.c.loco->problem(), kind);
    if (kind == SolverKind::BoxFddp) {
      const int nu = trot.c.loco->problem().maxNu();
      solver.setControlBounds(Eigen::VectorXd::Constant(nu, -1.0),
                              Eigen::VectorXd::Constant(nu, 1.0));
    }
    for (int threads : {1, 2}) {
      trot.c.loco->problem().setThreads(threads);
      // Warm-up: the first parallel region creates OpenMP's thread pool.
      ASSERT_TRUE(solver.setWarmStart(trot.xs, trot.us));
      solver.solve(1);
      const long n = allocations([&] {
        solver.setWarmStart(trot.xs, trot.us);
        solver.solve(5);
      });
      EXPECT_GT(solver.iterations(), 0);
      EXPECT_EQ(n, 0) << (kind == SolverKind::Fddp ? "Fddp, " : "BoxFddp, ") << threads
                      << " thread(s)";
    }
  }
}

// One receding-horizon tick's re-configuration: shift the knots and the warm start, re-plan the
// references (GaitGenerator::plan) and update the knots for the new start time.
TEST(SolverNoAllocation, ShiftAndUpdate) {
  Trot trot;
  LocomotionProblem& loco = *trot.c.loco;
  Solver solver(loco.problem(), SolverKind::Fddp);
  ASSERT_TRUE(solver.setWarmStart(trot.xs, trot.us));
  double t0 = 0.0;
  const double dt = loco.options().dt;
  for (int tick = 0; tick < 80; ++tick) {
    const long n = allocations([&] {
      loco.problem().shift(1);
      solver.shiftWarmStart(1);
      t0 += dt;
      EXPECT_TRUE(trot.c.update(t0));
    });
    EXPECT_EQ(n, 0) << "tick " << tick;
  }
  EXPECT_EQ(allocations([&] { trot.c.update(123.456); }), 0);
}

}  // namespace
}  // namespace stride
