// A short large-stride walk (paper §V-A; the full one is tools/paper/large-stride.sh): the IK
// baseline and KKT-DDP warm-started from it track the same contact sequence and centroidal
// reference on a 100 cm stride. Asserted is the physics, not exact numbers: the IK motion is
// kinematically exact and its forces carry the robot's weight, and DDP, which plans the swing
// leg's momentum over the horizon, needs a lower peak normal ground reaction force than the IK.

#include <gtest/gtest.h>

#include "tools/paper/large_stride.hpp"

namespace stride {
namespace {

const std::string kHumanoid = STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml";

// One full stride (plus the half steps that start and end the walk) at 40 ms knots and a few
// DDP iterations: the full run has 3 strides at 20 ms and 100 iterations.
constexpr double kStride = 1.0;
constexpr int kStrides = 1;
constexpr double kDt = 0.04;
constexpr int kIterations = 30;

// Suite named like the file, so that `ctest -R large_stride` finds it.
TEST(large_stride, DdpLowersThePeakNormalForceOfTheIkBaseline) {
  const Robot robot = loadRobot(kHumanoid);
  StridePlanOptions po;
  po.stride = kStride;
  po.strides = kStrides;
  po.dt = kDt;
  const std::array<std::string, 2> feet = {robot.contacts[0].frame, robot.contacts[1].frame};
  const StridePlan plan = planStrides(robot.model, robot.default_q, feet, po);
  const double weight = plan.mass * 9.81;

  // The IK follows the references and its forces explain its motion and carry the weight.
  const IkTrajectory ik = trackIk(robot.model, plan, robot.default_q);
  // (Centimetres at 100 cm: at touch-down the legs are at the edge of their reach.)
  EXPECT_LT(ik.max_foot_error, 0.03);
  EXPECT_LT(ik.max_com_error, 0.01);
  EXPECT_LT(ik.max_base_residual, 1e-6 * weight);
  EXPECT_NEAR(ik.force[0][0][2] + ik.force[0][1][2], weight, 0.01 * weight);
  const StrideMetrics m_ik = strideMetrics(robot.model, plan, ik.tau, ik.force);
  EXPECT_GT(m_ik.peak_normal_force_N, weight);  // a large stride is not quasi-static

  StrideProblem sp(robot, plan, StrideDdpOptions{});
  const StrideSolve solve = solveStrides(sp, ik, kIterations);
  ASSERT_GT(solve.iterations, 0);
  EXPECT_LT(solve.cost.back(), solve.cost.front());
  EXPECT_LT(solve.gap.back(), 1e-2);  // the DDP motion is (nearly) dynamically feasible
  const auto force = sp.forces(solve.xs, solve.us);
  std::vector<Eigen::VectorXd> tau(plan.N);
  for (int k = 0; k < plan.N; ++k) tau[k] = solve.us[sp.contactKnot(k)];
  const StrideMetrics m_ddp = strideMetrics(robot.model, plan, tau, force);
  // The DDP still walks: its feet land where planned (the forces are not lowered by not walking).
  const auto& x_end = solve.xs.back();
  EXPECT_NEAR(x_end[0], ik.q[plan.N][0],
              0.15);  // (ends ~9 cm behind the IK base: a lower CoM cost)
  EXPECT_LT(m_ddp.peak_normal_force_N, m_ik.peak_normal_force_N)
      << "IK " << m_ik.peak_normal_force_N << " N, DDP " << m_ddp.peak_normal_force_N << " N";
}

}  // namespace
}  // namespace stride
