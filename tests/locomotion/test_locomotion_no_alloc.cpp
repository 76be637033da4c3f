// The locomotion problem's tick does not touch the heap: a solve of the solo12 trot (FDDP and
// box-FDDP, Euler and RK4 knots: its swing, cone and impulse terms), LocomotionProblem::update
// after ShootingProblem::shift and Solver::shiftWarmStart, and 400 commanded ticks of
// GaitGenerator::plan with gait switches, and the planner's tick calls (Planner::setMap,
// beginTick, replan, the read-backs). The solver's own loop is checked on a problem without
// locomotion/ in tests/ocp/test_solver_no_alloc.cpp. As there, malloc and its relatives are
// interposed and counted (operator new and Eigen both end there), with Eigen's own check
// (EIGEN_RUNTIME_NO_MALLOC) armed as well; the interposition is per binary, hence this separate
// executable.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "locomotion/planner.hpp"
#include "locomotion_cases.hpp"
#include "solver/ddp/solver.hpp"

namespace stride {
namespace test_locomotion_no_alloc {

using test_support::AllocationCounter;
using test_support::allocations;

TEST(LocomotionNoAllocation, CounterSeesAllocations) {
  EXPECT_GE(allocations([] {
              Eigen::internal::set_is_malloc_allowed(true);
              std::vector<int> v(10);
              int* volatile data = v.data();  // volatile: clang may drop an unused allocation
              (void)data;
            }),
            1);
}

struct Trot {
  loco_cases::Case c;
  std::vector<Eigen::VectorXd> xs, us;
  explicit Trot(Integrator integrator = Integrator::Euler)
      : c(loco_cases::make(loco_cases::Problem::SoloTrot, STRIDE_SHARED_DIR,
                           [integrator](LocomotionOptions& o) { o.integrator = integrator; })) {
    c.warmStart(xs, us);
  }
};

// A few iterations of each solver from the trot's standing warm start (its copy included), after
// one warm-up solve, on one thread (the solver's loop with two: test_solver_no_alloc.cpp).
TEST(LocomotionNoAllocation, SolveTheTrot) {
  for (Integrator integrator : {Integrator::Euler, Integrator::Rk4}) {
    Trot trot(integrator);
    for (SolverKind kind : {SolverKind::Fddp, SolverKind::BoxFddp}) {
      Solver solver(trot.c.loco->problem(), kind);
      if (kind == SolverKind::BoxFddp) {
        const int nu = trot.c.loco->problem().maxNu();
        solver.setControlBounds(Eigen::VectorXd::Constant(nu, -1.0),
                                Eigen::VectorXd::Constant(nu, 1.0));
      }
      EXPECT_TRUE(solver.setWarmStart(trot.xs, trot.us));
      solver.solve(1);
      const long n = allocations([&] {
        solver.setWarmStart(trot.xs, trot.us);
        solver.solve(5);
      });
      EXPECT_GT(solver.iterations(), 0);
      EXPECT_EQ(n, 0) << (kind == SolverKind::Fddp ? "Fddp, " : "BoxFddp, ")
                      << toString(integrator);
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

// The commanded tick's re-planning: GaitGenerator::plan from a moving, displaced state with a
// changing command, gait switches (trot, stand, pace, and a pronk's flights) foot by foot,
// LocomotionProblem::update, and every query the knots and the controller make.
TEST(SolverNoAllocation, GaitGeneratorTicksWithGaitSwitches) {
  Trot trot;
  LocomotionProblem& loco = *trot.c.loco;
  GaitGenerator& gen = *trot.c.ref;
  ContactTimeline& timeline = gen.timeline();
  // Setup (allocates): more patterns.
  const int trot_id = timeline.patternAt(0.0);
  const int stand_id = timeline.addPattern(loco_cases::standing(*trot.c.robot, 0.5));
  ContactPlan pace = loco_cases::soloTrot(0.05, 0.15);
  pace.phases[1].contacts = {"FR_FOOT", "HR_FOOT"};
  pace.phases[3].contacts = {"FL_FOOT", "HL_FOOT"};
  const int pace_id = timeline.addPattern(pace);
  ContactPlan pronk;  // flights (issue 45): switched to and from foot by foot
  pronk.cyclic = true;
  pronk.phases = {{0.2, {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"}}, {0.15, {}}};
  const int pronk_id = timeline.addPattern(pronk);
  const int patterns[] = {stand_id, pace_id, pronk_id, trot_id, stand_id, pronk_id, trot_id};
  Eigen::VectorXd x = trot.c.robot->x_nominal, x_ref = x;
  const int nq = trot.c.robot->model.nq;
  const double dt = loco.options().dt;
  double t0 = 0.0, checksum = 0.0;
  int switches = 0;
  for (int tick = 0; tick < 400; ++tick) {
    const long n = allocations([&] {
      t0 += dt;
      // The robot drifts and turns a little, and moves faster than commanded.
      x[0] = 0.2 * t0;
      x[1] = 0.01 * std::sin(t0);
      const double yaw = 0.1 * std::sin(0.5 * t0);
      x.segment<4>(3) << 0.0, 0.0, std::sin(0.5 * yaw), std::cos(0.5 * yaw);
      x[nq] = 0.3;
      x[nq + 5] = 0.05;
      BodyCommand command;
      command.vx = 0.1 + 0.001 * (tick % 50);
      command.vy = -0.05;
      command.yaw_rate = 0.2;
      command.height = 0.01 * (tick % 3);
      gen.setCommand(command);
      if (tick % 37 == 36) {
        const double at = timeline.switchTo(patterns[switches % 7], t0);
        switches += at < ContactTimeline::kNever;
      }
      EXPECT_TRUE(gen.plan(t0, x, t0, t0 + loco.span()));
      EXPECT_TRUE(loco.update(t0, gen));
      for (int c = 0; c < 4; ++c) {
        const double t = t0 + 0.013 * (c + 1);
        checksum += gen.foot(c, t).sum() + gen.footRotation(c, t).trace();
        // (kNever after a stand: capped, to keep the sum finite)
        checksum +=
            gen.closed(c, t) + std::min(timeline.nextChange(c, t), 1e3) + timeline.lastChange(c, t);
        for (int i = 0; i < gen.stances(c); ++i) checksum += gen.stance(c, i).p.x();
      }
      gen.state(t0 + 0.5, x_ref);
      double vz = 0.0;
      checksum += x_ref.sum() + gen.com(t0 + 0.2).sum() + gen.basePosition(t0 + 0.3).sum() +
                  gen.baseYaw(t0 + 0.4) + gen.mask(t0 + 0.1) + timeline.patternAt(t0) +
                  gen.flightLift(t0 + 0.25, vz) + vz + gen.flights();
    });
    EXPECT_EQ(n, 0) << "tick " << tick;
  }
  EXPECT_EQ(switches, 10);
  EXPECT_TRUE(std::isfinite(checksum));
}

// The calls the controller's tick makes on the planner (locomotion/planner.hpp): maps taken and
// judged fresh or stale, gait switches (trot, stand, trot), the re-plan after a shift with the warm
// start carried and lifted legs re-seeded, and what the messages read back. stride_quad.
TEST(LocomotionNoAllocation, PlannerTicks) {
  const Robot robot =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  PlannerOptions options;
  options.locomotion.knots = 60;
  options.terrain.max_cells = 400;
  Planner planner(robot, options, "test");
  planner.build(0);  // setup: allocates
  LocomotionProblem& loco = planner.problem();
  Solver solver(loco.problem(), SolverKind::Fddp);
  terrain::ElevationMap map;
  map.origin_x = map.origin_y = -1.0;
  map.resolution = 0.1;
  map.rows = map.cols = 20;
  map.height.assign(400, 0.0f);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(robot.model.nq + robot.model.nv);
  x.head(robot.model.nq) = robot.default_q;
  const auto& gaits = planner.gaits();
  const int trot = static_cast<int>(std::find(gaits.begin(), gaits.end(), "trot") - gaits.begin());
  const double dt = loco.options().dt;
  double t_warm = 0.0, checksum = 0.0;
  int fresh = 0, stale = 0, switches = 0;
  for (int tick = 0; tick < 300; ++tick) {
    const long n = allocations([&] {
      const std::int64_t utime = 5000 * static_cast<std::int64_t>(tick);
      // Maps at 10 Hz for the first half; then none (the last one ages: blind).
      if (tick % 20 == 0 && tick < 150) checksum += planner.setMap(map, utime);
      BodyCommand command;
      command.vx = 0.2;
      const int gait = tick < 100 || tick >= 200 ? trot : 0;
      switches += gait != (tick == 0 ? -1 : (tick - 1 < 100 || tick - 1 >= 200 ? trot : 0));
      planner.setCommand(command, gait);
      const double t = planner.planTime(utime);
      x[0] = 0.2 * t;
      const MapChoice choice = planner.beginTick(t, utime, tick % 2 == 0 ? 0xFu : 0x9u);
      fresh += choice == MapChoice::Fresh;
      stale += choice == MapChoice::Stale;
      // The knots move by one whole knot every other tick (5 ms ticks, 10 ms knots).
      if (tick % 2 == 0 && tick > 0) {
        loco.problem().shift(1);
        t_warm += dt;
      }
      EXPECT_TRUE(planner.replan(t, x, t_warm, solver));
      checksum += planner.mask(t) + static_cast<double>(planner.gaitAt(t).size());
      planner.touchDowns(t, t_warm + 0.5, 4, 4, [&](int c, const GaitGenerator::Stance& s) {
        checksum += c + s.p.x();
        return true;
      });
    });
    EXPECT_EQ(n, 0) << "tick " << tick;
  }
  EXPECT_GT(fresh, 0);
  EXPECT_GT(stale, 0);
  EXPECT_EQ(switches, 3);
  EXPECT_TRUE(std::isfinite(checksum));
}

}  // namespace test_locomotion_no_alloc
}  // namespace stride
