// A short astronaut reorientation (paper §V-B; the full one is tools/paper/astronaut.sh): DDP from
// zero torques must turn the floating humanoid with its legs alone, and the plan must be
// physical: with no external force the angular momentum stays near zero (small next to what the
// legs carry), so the rotation comes from the shape cycles, not from momentum the integrator made
// up, and a finer integrator agrees on the angle.

#include <gtest/gtest.h>

#include "tools/paper/astronaut.hpp"

namespace stride {
namespace {

const std::string kHumanoid = STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml";
constexpr double kDeg = 180.0 / M_PI;

// 30 s of motion at dt = 40 ms (~5 s of solve): long enough for several leg cycles. The full
// experiment's 360° needs about 90 s of motion (tools/paper/README.md); this run is asked for 120°
// and must pass 60° (the issue asked for 180° in a short run: the formulation does not reach it,
// see the README).
constexpr double kShortDt = 0.04;
constexpr int kShortKnots = 750;
constexpr double kShortTurnDeg = 120.0;
constexpr int kShortWaypoints = 10;
constexpr int kShortIterations = 200;
constexpr double kPastDeg = 60.0;

TEST(Astronaut, LegsAloneTurnTheBaseWithoutMomentum) {
  const Robot robot = loadRobot(kHumanoid);
  AstronautOptions o;
  o.dt = kShortDt;
  o.knots = kShortKnots;
  o.turn_deg = kShortTurnDeg;
  o.waypoints = kShortWaypoints;
  AstronautProblem astro(robot, o);
  Solver solver(astro.problem(), SolverKind::Ddp);
  solver.solve(kShortIterations);  // from zero torques, as in the paper
  const AstronautMotion m = analyzeMotion(astro.model(), solver.xs(), o.dt);

  // The legs really move: each carries angular momentum, the whole body (almost) none.
  EXPECT_GT(m.max_h_leg, 0.5);
  EXPECT_LT(m.max_h, 0.1 * m.max_h_leg);
  EXPECT_LT(m.max_com_drift, 0.05);

  // Past kPastDeg, and monotonically from goal to goal: within a leg cycle the base swings back
  // and forth by tens of degrees, so the pitch is compared at the waypoints (a few cycles apart),
  // allowing 5° of that swing where the solver stalls near the end.
  EXPECT_GT(m.pitch.back() * kDeg, kPastDeg);
  double previous = 0.0;
  for (const auto& [k, goal] : astro.waypoints()) {
    EXPECT_GT(m.pitch[k] * kDeg, previous * kDeg - 5.0)
        << "at knot " << k << " (goal " << goal * kDeg << " deg)";
    previous = m.pitch[k];
  }

  // A 10 times finer integrator, knot by knot, turns the base by the same angle and creates far
  // less momentum per knot than the legs carry.
  const FineCheck fine = checkWithFinerSteps(astro.model(), solver.xs(), solver.us(), o.dt, 10);
  EXPECT_NEAR(fine.pitch * kDeg, m.pitch.back() * kDeg, 10.0);
  EXPECT_LT(fine.max_dh_fine, 0.05 * m.max_h_leg);
}

}  // namespace
}  // namespace stride
