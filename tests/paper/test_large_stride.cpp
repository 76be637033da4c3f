// A short large-stride walk (paper §V-A; the full one is tools/paper/large-stride.sh): the IK
// baseline and KKT-DDP warm-started from it track the same contact sequence and centroidal
// reference on a 100 cm stride. Asserted is the physics, not exact numbers: the IK motion is
// kinematically exact and its forces carry the robot's weight, DDP, which plans the swing leg's
// momentum over the horizon, needs a lower peak normal ground reaction force than the IK, and the
// mock robot (stride-sim's node in lock-step: sole corners, unilateral Coulomb contact, plastic
// impacts) plays the DDP motion's policy without falling, with the forces that were planned.

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "tools/paper/large_stride.hpp"
#include "tools/paper/stride_playback.hpp"

namespace stride {
namespace {

const std::string kHumanoid = STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml";

// One full stride (plus the half steps that start and end the walk) at 40 ms knots and a few
// DDP iterations: the full run has 3 strides and 100 iterations.
constexpr double kStride = 1.0;
constexpr int kStrides = 1;
constexpr double kDt = 0.04;
constexpr int kIterations = 30;

// Suite named like the file, so that `ctest -R large_stride` finds it. The plan, the IK and the
// DDP solve are shared by the tests.
class large_stride : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    robot_ = std::make_unique<Robot>(loadRobot(kHumanoid));
    StridePlanOptions po;
    po.stride = kStride;
    po.strides = kStrides;
    po.dt = kDt;
    const std::array<std::string, 2> feet = {robot_->contacts[0].frame, robot_->contacts[1].frame};
    plan_ = std::make_unique<StridePlan>(planStrides(robot_->model, robot_->default_q, feet, po));
    ik_ = std::make_unique<IkTrajectory>(trackIk(robot_->model, *plan_, robot_->default_q));
    sp_ = std::make_unique<StrideProblem>(*robot_, *plan_, StrideDdpOptions{});
    solve_ = std::make_unique<StrideSolve>(solveStrides(*sp_, *ik_, kIterations));
  }
  static void TearDownTestSuite() {
    solve_.reset();
    sp_.reset();
    ik_.reset();
    plan_.reset();
    robot_.reset();
  }
  static std::unique_ptr<Robot> robot_;
  static std::unique_ptr<StridePlan> plan_;
  static std::unique_ptr<IkTrajectory> ik_;
  static std::unique_ptr<StrideProblem> sp_;
  static std::unique_ptr<StrideSolve> solve_;
};
std::unique_ptr<Robot> large_stride::robot_;
std::unique_ptr<StridePlan> large_stride::plan_;
std::unique_ptr<IkTrajectory> large_stride::ik_;
std::unique_ptr<StrideProblem> large_stride::sp_;
std::unique_ptr<StrideSolve> large_stride::solve_;

TEST_F(large_stride, DdpLowersThePeakNormalForceOfTheIkBaseline) {
  const StridePlan& plan = *plan_;
  const IkTrajectory& ik = *ik_;
  const double weight = plan.mass * 9.81;

  // The IK follows the references and its forces explain its motion and carry the weight.
  // (Centimetres at 100 cm: at touch-down the legs are at the edge of their reach.)
  EXPECT_LT(ik.max_foot_error, 0.03);
  EXPECT_LT(ik.max_com_error, 0.01);
  EXPECT_LT(ik.max_base_residual, 1e-6 * weight);
  EXPECT_NEAR(ik.force[0][0][2] + ik.force[0][1][2], weight, 0.01 * weight);
  const StrideMetrics m_ik = strideMetrics(robot_->model, plan, ik.tau, ik.force);
  EXPECT_GT(m_ik.peak_normal_force_N, weight);  // a large stride is not quasi-static

  const StrideSolve& solve = *solve_;
  ASSERT_GT(solve.iterations, 0);
  EXPECT_LT(solve.cost.back(), solve.cost.front());
  EXPECT_LT(solve.gap.back(), 1e-2);  // the DDP motion is (nearly) dynamically feasible
  const auto force = sp_->forces(solve.xs, solve.us);
  std::vector<Eigen::VectorXd> tau(plan.N);
  for (int k = 0; k < plan.N; ++k) tau[k] = solve.us[sp_->contactKnot(k)];
  const StrideMetrics m_ddp = strideMetrics(robot_->model, plan, tau, force);
  // The DDP still walks: its feet land where planned (the forces are not lowered by not walking).
  const auto& x_end = solve.xs.back();
  EXPECT_NEAR(x_end[0], ik.q[plan.N][0],
              0.15);  // (ends ~9 cm behind the IK base: a lower CoM cost)
  EXPECT_LT(m_ddp.peak_normal_force_N, m_ik.peak_normal_force_N)
      << "IK " << m_ik.peak_normal_force_N << " N, DDP " << m_ddp.peak_normal_force_N << " N";
}

// The DDP motion's policy (feed-forward and states of the DDP solution, TVLQR gains) played open
// loop on stride-sim's node in lock-step, then standing: every estimate answered, every policy
// accepted, no fall, both feet down where the walk ends, the base within 3 cm of the plan, and the
// measured peak normal force within 5% of the planned one as a mean over a knot (the plan's
// resolution) and within 10% per 1 ms step (no impact spikes: with the velocity reference at the
// knots instead of their middles the 1 ms peak is 2-4 times the plan's).
TEST_F(large_stride, MockRobotPlaysTheDdpStrideWithThePlannedForces) {
  StrideSimOptions so;
  so.hold_s = 0.5;
  const StrideSimResult sim = simulateStrides(*robot_, *sp_, *solve_, so);
  EXPECT_FALSE(sim.fell) << "fell at " << sim.fall_time << " s";
  EXPECT_TRUE(sim.completed) << "final base error " << sim.final_base_error << " m";
  EXPECT_LT(sim.max_base_error, 0.03);
  EXPECT_GT(sim.policies, 0);
  EXPECT_EQ(sim.unanswered, 0);
  EXPECT_EQ(sim.policies_rejected, 0);
  EXPECT_EQ(sim.hold_steps, 0) << "the node applied its hold PD: a step had no policy";
  EXPECT_EQ(sim.exhausted_steps, 0) << "a step ran past the policy it had";
  const auto force = sp_->forces(solve_->xs, solve_->us);
  std::vector<Eigen::VectorXd> tau(plan_->N);
  for (int k = 0; k < plan_->N; ++k) tau[k] = solve_->us[sp_->contactKnot(k)];
  const double planned = strideMetrics(robot_->model, *plan_, tau, force).peak_normal_force_N;
  const double measured = std::max(sim.peak_normal_force_knot[0], sim.peak_normal_force_knot[1]);
  std::printf(
      "playback: peak normal force %.0f N (knot mean; 1 ms %.0f N), planned %.0f N, "
      "max base drift %.3f m, max tilt %.1f deg\n",
      measured, std::max(sim.peak_normal_force[0], sim.peak_normal_force[1]), planned,
      sim.max_base_error, sim.max_tilt_deg);
  EXPECT_NEAR(measured, planned, 0.05 * planned);
  EXPECT_NEAR(std::max(sim.peak_normal_force[0], sim.peak_normal_force[1]), planned, 0.1 * planned);
}

}  // namespace
}  // namespace stride
