// Model loading: URDF structure, joint order, merged fixed bodies, frames, limits, SRDF postures,
// and every kind of bad input getting an error that names the file and the element.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "solver/multibody/aba.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/srdf.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace {

// A small arm: continuous shoulder, revolute elbow, prismatic slide, and fixed links around them.
// Sibling joints "b_joint" and "a_joint" are listed out of name order on purpose.
const char* kArm = R"(<?xml version="1.0"?>
<robot name="arm">
  <link name="base"><inertial><origin xyz="0 0 0.05"/><mass value="2"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="upper"><inertial><origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/><mass value="1"/>
    <inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0.001" ixz="0" iyz="0"/></inertial></link>
  <link name="sensor"><inertial><origin xyz="0.01 0 0"/><mass value="0.5"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="lower"><inertial><origin xyz="0 0 0.1"/><mass value="0.7"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="slider"><inertial><origin xyz="0 0 0"/><mass value="0.2"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tool"/>
  <joint name="shoulder" type="continuous"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit effort="50" velocity="3"/></joint>
  <joint name="b_joint" type="revolute"><parent link="upper"/><child link="lower"/>
    <origin xyz="0 0 0.2" rpy="0 0.3 0"/><axis xyz="0 1 1"/>
    <limit lower="-1" upper="1.5" effort="20" velocity="2"/></joint>
  <joint name="a_joint" type="prismatic"><parent link="upper"/><child link="slider"/>
    <origin xyz="0.05 0 0.1"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.1" effort="100" velocity="0.5"/></joint>
  <joint name="sensor_mount" type="fixed"><parent link="upper"/><child link="sensor"/>
    <origin xyz="0 0.05 0.15" rpy="0.5 0 0"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="lower"/><child link="tool"/>
    <origin xyz="0 0 0.25"/></joint>
</robot>)";

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

void expectError(const std::string& xml, const std::string& fragment) {
  try {
    buildModelFromUrdfString(xml, RootJoint::Fixed, "broken.urdf");
    ADD_FAILURE() << "no error; expected one mentioning '" << fragment << "'";
  } catch (const UrdfError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("broken.urdf"), std::string::npos) << msg;
    EXPECT_NE(msg.find(fragment), std::string::npos) << msg;
  }
}

TEST(Urdf, StructureOrderAndLimits) {
  const Model model = buildModelFromUrdfString(kArm, RootJoint::Fixed);
  EXPECT_EQ(model.name, "arm");
  ASSERT_EQ(model.njoints(), 4);  // universe + 3 moving joints
  EXPECT_EQ(model.nq, 3);         // continuous counts as one angle
  EXPECT_EQ(model.nv, 3);
  // Depth-first, siblings by name: shoulder, then a_joint before b_joint.
  EXPECT_EQ(model.joints[1].name, "shoulder");
  EXPECT_EQ(model.joints[2].name, "a_joint");
  EXPECT_EQ(model.joints[3].name, "b_joint");
  EXPECT_EQ(model.joints[2].type, JointType::Prismatic);
  EXPECT_EQ(model.joints[3].type, JointType::Revolute);
  EXPECT_EQ(model.joints[1].alignedAxis, 2);
  EXPECT_EQ(model.joints[3].alignedAxis, -1);
  EXPECT_NEAR(model.joints[3].axis.norm(), 1.0, 1e-15);
  // Limits: continuous has none on position; the others keep theirs.
  EXPECT_TRUE(std::isinf(model.lowerPositionLimit[0]));
  EXPECT_DOUBLE_EQ(model.effortLimit[0], 50);
  EXPECT_DOUBLE_EQ(model.velocityLimit[0], 3);
  EXPECT_DOUBLE_EQ(model.lowerPositionLimit[2], -1);
  EXPECT_DOUBLE_EQ(model.upperPositionLimit[2], 1.5);
  EXPECT_DOUBLE_EQ(model.upperPositionLimit[1], 0.1);
  // Every link and joint is a frame, with the right kind and parent joint.
  for (const char* name : {"base", "upper", "sensor", "lower", "slider", "tool", "shoulder",
                           "a_joint", "b_joint", "sensor_mount", "tool_joint"})
    EXPECT_TRUE(model.existFrame(name)) << name;
  EXPECT_EQ(model.frames[model.getFrameId("sensor")].type, FrameType::Body);
  EXPECT_EQ(model.frames[model.getFrameId("sensor_mount")].type, FrameType::FixedJoint);
  EXPECT_EQ(model.frames[model.getFrameId("tool")].parentJoint, model.getJointId("b_joint"));
  EXPECT_EQ(model.frames[model.getFrameId("base")].parentJoint, 0);
  EXPECT_THROW(model.getFrameId("nope"), std::out_of_range);
}

TEST(Urdf, FixedLinksAreMergedWithTheirMass) {
  const Model model = buildModelFromUrdfString(kArm, RootJoint::Fixed);
  // The fixed base stays with the universe; the sensor merges into the shoulder's body.
  EXPECT_DOUBLE_EQ(model.fixedMass(), 2.0);
  EXPECT_DOUBLE_EQ(model.inertias[model.getJointId("shoulder")].m, 1.5);
  EXPECT_DOUBLE_EQ(model.totalMass(), 1.0 + 0.5 + 0.7 + 0.2);
  // The merged body's centre of mass is the mass-weighted mean of the two, in the joint frame.
  const Eigen::Vector3d sensor_com =
      Eigen::Vector3d(0, 0.05, 0.15) +
      Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()) * Eigen::Vector3d(0.01, 0, 0);
  const Eigen::Vector3d expected = (1.0 * Eigen::Vector3d(0, 0, 0.1) + 0.5 * sensor_com) / 1.5;
  EXPECT_LT((model.inertias[model.getJointId("shoulder")].com() - expected).norm(), 1e-14);
}

TEST(Urdf, FreeFlyerRoot) {
  const Model model = buildModelFromUrdfString(kArm, RootJoint::FreeFlyer);
  EXPECT_EQ(model.nq, 10);
  EXPECT_EQ(model.nv, 9);
  EXPECT_EQ(model.joints[1].type, JointType::FreeFlyer);
  EXPECT_EQ(model.joints[1].name, "root_joint");
  EXPECT_DOUBLE_EQ(model.totalMass(), 4.4);  // the base now moves
  EXPECT_EQ(model.frames[model.getFrameId("base")].parentJoint, 1);
}

TEST(Urdf, BadInputNamesFileAndElement) {
  EXPECT_THROW(buildModelFromUrdf("/nonexistent/robot.urdf", RootJoint::Fixed), UrdfError);
  try {
    buildModelFromUrdf("/nonexistent/robot.urdf", RootJoint::Fixed);
  } catch (const UrdfError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.urdf"), std::string::npos);
  }
  expectError("<robot name='x'><link name='a'></robot>", "malformed XML at line 1");
  expectError("<model/>", "root element must be <robot>");
  expectError("<robot name='x'/>", "no <link>");
  expectError(replace(kArm, "type=\"prismatic\"", "type=\"floating\""),
              "joint 'a_joint' has type 'floating'");
  expectError(replace(kArm, "type=\"prismatic\"", "type=\"planar\""), "'planar'");
  expectError(replace(kArm, "<child link=\"slider\"/>", "<child link=\"lower\"/>"),
              "link 'lower' is the child of two joints");
  expectError(replace(kArm, "<child link=\"slider\"/>", "<child link=\"nowhere\"/>"),
              "child link 'nowhere' that does not exist");
  // A loop with no root left: base becomes the child of the tool.
  expectError(replace(kArm, "</robot>",
                      "<joint name='back' type='fixed'><parent link='tool'/><child "
                      "link='base'/></joint></robot>"),
              "no root link");
  // Two roots.
  expectError(
      replace(kArm, "<link name=\"tool\"/>", "<link name=\"tool\"/><link name=\"island\"/>"),
      "several root links");
  // A cycle that does not reach the root.
  expectError(
      replace(kArm, "</robot>",
              "<link name='p'/><link name='r'/>"
              "<joint name='pr' type='fixed'><parent link='p'/><child link='r'/></joint>"
              "<joint name='rp' type='fixed'><parent link='r'/><child link='p'/></joint></robot>"),
      "kinematic loop");
  expectError(replace(kArm, "<axis xyz=\"1 0 0\"/>", "<axis xyz=\"0 0 0\"/>"),
              "'a_joint' has a zero <axis>");
  expectError(replace(kArm, "lower=\"-1\" upper=\"1.5\"", "lower=\"2\" upper=\"1.5\""),
              "lower limit above");
  expectError(replace(kArm, "<mass value=\"0.7\"/>", "<mass value=\"abc\"/>"),
              "link 'lower' <inertial> <mass> has value='abc', not a finite number");
  expectError(replace(kArm, "<mass value=\"0.7\"/>", "<mass value=\"-1\"/>"), "negative mass");
  expectError(replace(kArm, "ixx=\"0.02\" ", ""), "link 'upper' <inertial> <inertia> has no 'ixx'");
  expectError(replace(kArm, "izz=\"0.002\"", "izz=\"-0.5\""), "not positive semi-definite");
  // What only urdfdom checks still comes back with its own words.
  expectError(
      replace(kArm, "<limit lower=\"0\" upper=\"0.1\" effort=\"100\" velocity=\"0.5\"/>", ""),
      "PRISMATIC without limits");
}

TEST(Urdf, WrongSizesAreCaughtAtTheBoundary) {
  const Model model = buildModelFromUrdfString(kArm, RootJoint::FreeFlyer);
  Data data(model);
  const Eigen::VectorXd q = neutral(model), v = Eigen::VectorXd::Zero(model.nv);
  EXPECT_THROW(rnea(model, data, v, v, v), std::invalid_argument);  // q has nv entries
  EXPECT_THROW(aba(model, data, q, q, v), std::invalid_argument);   // v has nq entries
  EXPECT_THROW(rnea(model, data, q, v, Eigen::VectorXd::Zero(3)), std::invalid_argument);
  try {
    rnea(model, data, v, v, v);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'q' has size 9, expected 10"), std::string::npos)
        << e.what();
  }
}

TEST(Urdf, EverySharedRobotLoads) {
  // nv with a free-flyer root, as the files describe them (fixed joints merged).
  const std::vector<std::pair<std::string, int>> robots = {
      {"anymal/anymal.urdf", 18},       {"anymal_c/anymal.urdf", 18},
      {"bolt/bolt.urdf", 12},           {"hyq/hyq_no_sensors.urdf", 18},
      {"panda/panda.urdf", 15},         {"solo12/solo.urdf", 14},
      {"solo12/solo12.urdf", 18},       {"talos/talos_full_v2.urdf", 50},
      {"talos/talos_reduced.urdf", 38}, {"ur5/ur5_robot.urdf", 12}};
  for (const auto& [file, nv] : robots) {
    const Model model =
        buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/" + file, RootJoint::FreeFlyer);
    EXPECT_EQ(model.nv, nv) << file;
    EXPECT_GT(model.totalMass(), 0.5) << file;
  }
  // ANYmal C has a link and a joint both named LF_HAA: both stay reachable as frames.
  const Model anymal =
      buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/anymal_c/anymal.urdf", RootJoint::FreeFlyer);
  EXPECT_EQ(anymal.frames[anymal.getFrameId("LF_HAA", FrameType::Joint)].type, FrameType::Joint);
  EXPECT_EQ(anymal.frames[anymal.getFrameId("LF_HAA", FrameType::Body)].type, FrameType::Body);
}

TEST(Srdf, ReferenceConfigurations) {
  Model solo =
      buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/solo12/solo12.urdf", RootJoint::FreeFlyer);
  const SrdfReport report =
      loadReferenceConfigurations(solo, STRIDE_SHARED_DIR "/robots/solo12/solo.srdf");
  ASSERT_TRUE(solo.referenceConfigurations.count("standing"));
  const Eigen::VectorXd& q = solo.referenceConfigurations["standing"];
  EXPECT_DOUBLE_EQ(q[2], 0.235);
  EXPECT_DOUBLE_EQ(q[6], 1.0);
  EXPECT_DOUBLE_EQ(q[solo.joints[solo.getJointId("FL_HAA")].idx_q], 0.1);
  EXPECT_DOUBLE_EQ(q[solo.joints[solo.getJointId("FL_HFE")].idx_q], 0.8);
  EXPECT_TRUE(report.ignored_joints.empty());

  // The full Talos SRDF against the reduced model: extra joints are reported, not fatal.
  Model talos = buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/talos/talos_reduced.urdf",
                                   RootJoint::FreeFlyer);
  const SrdfReport tr =
      loadReferenceConfigurations(talos, STRIDE_SHARED_DIR "/robots/talos/talos.srdf");
  ASSERT_TRUE(talos.referenceConfigurations.count("half_sitting"));
  EXPECT_NEAR(talos.referenceConfigurations["half_sitting"][2], 1.01927, 1e-12);
}

TEST(Srdf, BadInput) {
  Model model = buildModelFromUrdfString(kArm, RootJoint::FreeFlyer);
  EXPECT_THROW(loadReferenceConfigurations(model, "/nonexistent.srdf"), UrdfError);
  const std::string path = ::testing::TempDir() + "/bad.srdf";
  std::ofstream(path) << "<robot name='arm'><group_state name='s' group='all'>"
                         "<joint name='root_joint' value='0 0 1'/></group_state></robot>";
  try {
    loadReferenceConfigurations(model, path);
    ADD_FAILURE() << "a 3-number free-flyer value was accepted";
  } catch (const UrdfError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'root_joint' needs 7 number(s)"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace stride
