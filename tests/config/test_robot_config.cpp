// The in-house robots load with the properties their issue asked for, and bad YAML is reported
// with the file and the key.

#include <gtest/gtest.h>

#include <fstream>

#include "config/robot_config.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/frames.hpp"

namespace stride {
namespace {

const std::string kQuad = STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml";
const std::string kHumanoid = STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml";

// Contacts touch the ground (z = 0) in the default posture and the CoM is above them.
void expectStandsOnTheGround(const Robot& robot) {
  Data data(robot.model);
  framesForwardKinematics(robot.model, data, robot.default_q);
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const auto& c : robot.contacts) {
    const SE3& oMf = data.oMf[robot.model.getFrameId(c.frame)];
    EXPECT_NEAR(oMf.p.z(), 0.0, 1e-6) << c.frame;
    if (c.dim == 6) {
      EXPECT_NEAR(oMf.R(2, 2), 1.0, 1e-9) << c.frame << " sole is not flat";
    }
    lo = lo.cwiseMin(oMf.p.head<2>());
    hi = hi.cwiseMax(oMf.p.head<2>());
  }
  const Eigen::Vector3d com = centerOfMass(robot.model, data, robot.default_q);
  EXPECT_GT(com.z(), 0.1);
  EXPECT_TRUE((com.head<2>().array() >= lo.array() - robot.sole_half_extents.array()).all() &&
              (com.head<2>().array() <= hi.array() + robot.sole_half_extents.array()).all())
      << "CoM " << com.transpose() << " is outside the support polygon";
}

TEST(RobotConfig, Quadruped) {
  const Robot robot = loadRobot(kQuad);
  EXPECT_EQ(robot.name, "stride_quad");
  EXPECT_EQ(robot.model.nv, 18);
  EXPECT_EQ(robot.model.nq, 19);
  EXPECT_NEAR(robot.model.totalMass(), 2.5, 0.1);
  ASSERT_EQ(robot.contacts.size(), 4u);
  for (const auto& c : robot.contacts) EXPECT_EQ(c.dim, 3);
  EXPECT_DOUBLE_EQ(robot.model.effortLimit[6], 2.7);
  EXPECT_TRUE(robot.model.referenceConfigurations.count("default"));
  expectStandsOnTheGround(robot);
}

TEST(RobotConfig, Humanoid) {
  const Robot robot = loadRobot(kHumanoid);
  EXPECT_EQ(robot.name, "stride_humanoid");
  EXPECT_GE(robot.model.totalMass(), 58.0);
  EXPECT_LE(robot.model.totalMass(), 65.0);
  ASSERT_EQ(robot.contacts.size(), 2u);
  for (const auto& c : robot.contacts) EXPECT_EQ(c.dim, 6);
  // 6-joint legs.
  for (const char* side : {"L", "R"})
    for (const char* j : {"hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle_pitch", "ankle_roll"})
      EXPECT_TRUE(robot.model.existJoint(std::string(side) + "_" + j));
  expectStandsOnTheGround(robot);
  // About 1.6 m tall when straight: the head frame is between 1.4 and 1.7 m above the soles.
  Data data(robot.model);
  Eigen::VectorXd q = robot.default_q;
  q.tail(robot.model.nq - 7).setZero();
  framesForwardKinematics(robot.model, data, q);
  const double height = data.oMf[robot.model.getFrameId("head")].p.z() -
                        data.oMf[robot.model.getFrameId("L_sole")].p.z();
  EXPECT_GT(height, 1.3);
  EXPECT_LT(height, 1.7);
}

void expectConfigError(const std::string& yaml, const std::string& fragment) {
  const std::string path = STRIDE_CONFIG_DIR "/robots/stride_quad/test_broken.yaml";
  { std::ofstream(path) << yaml; }
  try {
    loadRobot(path);
    ADD_FAILURE() << "accepted; expected an error with '" << fragment << "'";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("test_broken.yaml"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

TEST(RobotConfig, BadInput) {
  EXPECT_THROW(loadRobot("/nonexistent.yaml"), ConfigError);
  std::ifstream in(kQuad);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const auto pos = s.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    return s.replace(pos, from.size(), to);
  };
  expectConfigError("name: [unclosed", "malformed YAML");
  expectConfigError(with("name: stride_quad", "nom: stride_quad"), "missing key 'name'");
  expectConfigError(with("{frame: FL_foot, dim: 3}", "{frame: FL_toe, dim: 3}"),
                    "contact frame 'FL_toe'");
  expectConfigError(with("{frame: FL_foot, dim: 3}", "{frame: FL_foot, dim: 4}"), "dim 4");
  expectConfigError(with("FL_HAA: 2.7,", ""), "torque_limits has no entry for joint 'FL_HAA'");
  expectConfigError(with("FL_HAA: 2.7,", "FL_HAA: -1,"), "must be positive");
  expectConfigError(with("urdf: stride_quad.urdf", "urdf: missing.urdf"), "does not exist");
  expectConfigError(with("root_joint: free-flyer", "root_joint: planar"), "root_joint must be");
  expectConfigError(with("0.0, 0.0, 0.0, 1.0]", "0.0, 0.0, 0.5, 1.0]"), "quaternion is not unit");
}

}  // namespace
}  // namespace stride
