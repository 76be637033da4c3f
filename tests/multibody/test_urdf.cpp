// Model loading: URDF structure, joint order, merged fixed bodies, frames, limits, SRDF postures,
// and every kind of bad input getting an error that names the file and the element.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include "solver/multibody/aba.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/srdf.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace test_urdf {

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

void expectError(const std::string& xml, const std::string& fragment,
                 const std::map<std::string, double>& locked = {},
                 RootJoint root = RootJoint::Fixed) {
  try {
    buildModelFromUrdfString(xml, root, locked, "broken.urdf");
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
  // The model's actuated dimension (model.hpp): the free-flyer's 6 are not actuated, every joint
  // below it is; a fixed base actuates all of its joints.
  EXPECT_EQ(actuatedDimension(model), 3);
  EXPECT_EQ(actuatedDimension(buildModelFromUrdfString(kArm, RootJoint::Fixed)), 3);
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

// The frames of `locked` (a model with joints locked) at q_locked are where the same frames of
// `full` are at q_full: compared by name, every frame of the locked model.
void expectSameFramePlacements(const Model& full, const Eigen::VectorXd& q_full,
                               const Model& locked, const Eigen::VectorXd& q_locked) {
  Data df(full), dl(locked);
  framesForwardKinematics(full, df, q_full);
  framesForwardKinematics(locked, dl, q_locked);
  ASSERT_EQ(full.frames.size(), locked.frames.size());
  for (std::size_t f = 1; f < locked.frames.size(); ++f) {
    const std::string& name = locked.frames[f].name;
    const SE3& a = dl.oMf[f];
    const SE3& b = df.oMf[full.getFrameId(name)];
    EXPECT_LT((a.R - b.R).norm() + (a.p - b.p).norm(), 1e-12) << name;
  }
}

// The configuration of `full` whose joints are those of `locked` at q_locked, the others at `at`.
Eigen::VectorXd fullConfiguration(const Model& full, const Model& locked,
                                  const Eigen::VectorXd& q_locked,
                                  const std::map<std::string, double>& at) {
  Eigen::VectorXd q = neutral(full);
  for (int i = 1; i < locked.njoints(); ++i) {
    const Joint& jl = locked.joints[i];
    const Joint& jf = full.joints[full.getJointId(jl.name)];
    q.segment(jf.idx_q, jf.nq) = q_locked.segment(jl.idx_q, jl.nq);
  }
  for (const auto& [name, angle] : at) q[full.joints[full.getJointId(name)].idx_q] = angle;
  return q;
}

TEST(Urdf, LockedJointIsAFixedJointAtItsAngle) {
  const Model full = buildModelFromUrdfString(kArm, RootJoint::FreeFlyer);
  std::mt19937 rng(34);
  // Revolute about a non-aligned axis, prismatic, continuous; then two at once.
  const std::vector<std::map<std::string, double>> cases = {{{"b_joint", 0.7}},
                                                            {{"a_joint", 0.06}},
                                                            {{"shoulder", -2.5}},
                                                            {{"b_joint", -0.4}, {"a_joint", 0.02}}};
  for (const auto& lock : cases) {
    const Model locked = buildModelFromUrdfString(kArm, RootJoint::FreeFlyer, lock);
    const int n = static_cast<int>(lock.size());
    EXPECT_EQ(locked.nq, full.nq - n);
    EXPECT_EQ(locked.nv, full.nv - n);
    EXPECT_EQ(locked.njoints(), full.njoints() - n);
    EXPECT_NEAR(locked.totalMass(), full.totalMass(), 1e-14);
    for (const auto& [name, angle] : lock) {
      EXPECT_FALSE(locked.existJoint(name)) << name;
      // Its frame stays, as a fixed joint's: it owns no coordinate.
      EXPECT_EQ(locked.frames[locked.getFrameId(name)].type, FrameType::FixedJoint) << name;
    }
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::VectorXd q = trial == 0 ? neutral(locked) : randomConfiguration(locked, rng);
      expectSameFramePlacements(full, fullConfiguration(full, locked, q, lock), locked, q);
    }
  }
  // The elbow's child bodies merge into the shoulder's body, as a fixed joint's would.
  const Model no_elbow = buildModelFromUrdfString(kArm, RootJoint::Fixed, {{"b_joint", 0.7}});
  EXPECT_EQ(no_elbow.frames[no_elbow.getFrameId("lower")].parentJoint,
            no_elbow.getJointId("shoulder"));
  EXPECT_NEAR(no_elbow.inertias[no_elbow.getJointId("shoulder")].m, 1.0 + 0.5 + 0.7, 1e-14);
  // Nothing locked: the same model as the two-argument builder's.
  EXPECT_EQ(buildModelFromUrdfString(kArm, RootJoint::Fixed, std::map<std::string, double>{}).nv,
            3);
}

TEST(Urdf, BadLockedJointsAreRefused) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expectError(kArm, "locked joint 'elbow' is not a joint of this URDF", {{"elbow", 0.0}});
  expectError(kArm, "locked joint 'upper' is not a joint", {{"upper", 0.0}});  // a link
  expectError(kArm, "locked joint 'sensor_mount' is a fixed joint", {{"sensor_mount", 0.0}});
  expectError(kArm, "locked joint 'root_joint' is the free-flyer root", {{"root_joint", 0.0}},
              RootJoint::FreeFlyer);
  expectError(kArm, "joint 'b_joint' locked at 2 rad, outside its limits [-1, 1.5] rad",
              {{"b_joint", 2.0}});
  expectError(kArm, "joint 'b_joint' locked at -1.25 rad, outside its limits [-1, 1.5] rad",
              {{"b_joint", -1.25}});
  expectError(kArm, "joint 'a_joint' locked at 0.2 m, outside its limits [0, 0.1] m",
              {{"a_joint", 0.2}});
  expectError(kArm, "joint 'shoulder' locked at nan: not a finite number", {{"shoulder", nan}});
  expectError(kArm, "not a finite number", {{"shoulder", std::numeric_limits<double>::infinity()}});
  // The limits themselves are allowed; a continuous joint has none.
  EXPECT_EQ(buildModelFromUrdfString(kArm, RootJoint::Fixed, {{"b_joint", 1.5}, {"a_joint", 0}}).nv,
            1);
  EXPECT_EQ(buildModelFromUrdfString(kArm, RootJoint::Fixed, {{"shoulder", 40.0}}).nv, 2);
}

// kArm with a gripper on the elbow's link: a motor and two mimic fingers, the second mimicking the
// first (a chain), and a fixed joint whose mimic tag couples nothing.
std::string armWithGripper() {
  return replace(kArm, "</robot>", R"(
  <link name="palm"/>
  <link name="finger_a"><inertial><mass value="0.1"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_b"><inertial><origin xyz="0 0.02 0"/><mass value="0.1"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="pad"/>
  <joint name="gripper" type="prismatic"><parent link="lower"/><child link="palm"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.04" effort="10" velocity="0.1"/></joint>
  <joint name="finger_a_joint" type="revolute"><parent link="palm"/><child link="finger_a"/>
    <origin xyz="0 0.03 0" rpy="0.2 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
    <mimic joint="gripper" multiplier="-30" offset="0.1"/></joint>
  <joint name="finger_b_joint" type="revolute"><parent link="palm"/><child link="finger_b"/>
    <origin xyz="0 -0.03 0"/><axis xyz="0 1 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
    <mimic joint="finger_a_joint" multiplier="0.5"/></joint>
  <joint name="pad_joint" type="fixed"><parent link="finger_b"/><child link="pad"/>
    <origin xyz="0 0 0.05"/><mimic joint="gripper"/></joint>
</robot>)");
}

TEST(Urdf, MimicJointsFollowTheirLockedLeader) {
  const std::string xml = armWithGripper();
  // Listed, moving ones only, in file order, multiplier 1 and offset 0 by default.
  const std::vector<MimicJoint> mimics = urdfMimicJointsFromString(xml);
  ASSERT_EQ(mimics.size(), 2u);
  EXPECT_EQ(mimics[0].name, "finger_a_joint");
  EXPECT_EQ(mimics[0].leader, "gripper");
  EXPECT_DOUBLE_EQ(mimics[0].multiplier, -30);
  EXPECT_DOUBLE_EQ(mimics[0].offset, 0.1);
  EXPECT_EQ(mimics[1].name, "finger_b_joint");
  EXPECT_EQ(mimics[1].leader, "finger_a_joint");
  EXPECT_DOUBLE_EQ(mimics[1].multiplier, 0.5);
  EXPECT_DOUBLE_EQ(mimics[1].offset, 0.0);
  EXPECT_TRUE(urdfMimicJointsFromString(kArm).empty());

  // Not locked: refused, every free mimic joint named, and what to do.
  expectError(xml,
              "joint 'finger_a_joint' mimics 'gripper' (multiplier -30, offset 0.1); joint "
              "'finger_b_joint' mimics 'finger_a_joint' (multiplier 0.5, offset 0): Stride has no "
              "coupled joints; lock 'gripper', 'finger_a_joint' (locked_joints) and their mimics "
              "follow");
  // The leader locked: both fingers follow (the second through the first).
  const double g = 0.015, a = -30 * g + 0.1, b = 0.5 * a;
  const Model locked = buildModelFromUrdfString(xml, RootJoint::FreeFlyer, {{"gripper", g}});
  EXPECT_EQ(locked.nv, 6 + 3);
  for (const char* name : {"gripper", "finger_a_joint", "finger_b_joint"}) {
    EXPECT_FALSE(locked.existJoint(name)) << name;
    EXPECT_EQ(locked.frames[locked.getFrameId(name)].type, FrameType::FixedJoint) << name;
  }
  // Same frames as a model without the mimic tags at those angles.
  std::string uncoupled = xml;
  for (const char* tag :
       {R"(<mimic joint="gripper" multiplier="-30" offset="0.1"/>)",
        R"(<mimic joint="finger_a_joint" multiplier="0.5"/>)", R"(<mimic joint="gripper"/>)"})
    uncoupled = replace(uncoupled, tag, "");
  const Model full = buildModelFromUrdfString(uncoupled, RootJoint::FreeFlyer);
  EXPECT_EQ(full.nv, 6 + 6);
  EXPECT_NEAR(locked.totalMass(), full.totalMass(), 1e-14);
  std::mt19937 rng(7);
  const std::map<std::string, double> at = {
      {"gripper", g}, {"finger_a_joint", a}, {"finger_b_joint", b}};
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd q = randomConfiguration(locked, rng);
    expectSameFramePlacements(full, fullConfiguration(full, locked, q, at), locked, q);
  }
  // Locking the first finger itself is enough for the second; its own leader stays a motor.
  const Model fingers = buildModelFromUrdfString(xml, RootJoint::Fixed, {{"finger_a_joint", 0.3}});
  EXPECT_EQ(fingers.nv, 4);
  EXPECT_TRUE(fingers.existJoint("gripper"));
  // A mimic locked explicitly must agree with its locked leader.
  EXPECT_EQ(
      buildModelFromUrdfString(xml, RootJoint::Fixed, {{"gripper", g}, {"finger_b_joint", b}}).nv,
      3);
  expectError(xml, "joint 'finger_b_joint' is locked at 0.5 but must be at -0.175",
              {{"gripper", g}, {"finger_b_joint", 0.5}});
  // A follower pushed out of its limits by its leader's angle.
  expectError(xml,
              "joint 'finger_a_joint' locked at -1.1 rad (it mimics 'gripper' locked at 0.04: "
              "multiplier -30, offset 0.1), outside its limits [-1, 1] rad",
              {{"gripper", 0.04}});
  // Bad tags.
  expectError(replace(xml, R"(<mimic joint="gripper" multiplier="-30")",
                      R"(<mimic joint="grip" multiplier="-30")"),
              "joint 'finger_a_joint' mimics 'grip', which is not a joint (line");
  expectError(replace(xml, R"(multiplier="0.5")", R"(multiplier="half")"),
              "joint 'finger_b_joint' <mimic> has multiplier='half', not a finite number");
}

TEST(Urdf, FullTalosNeedsItsGrippersLockedForControl) {
  const std::string path = STRIDE_SHARED_DIR "/robots/talos/talos_full_v2.urdf";
  // 12 mimic finger joints, six per gripper.
  const std::vector<MimicJoint> mimics = urdfMimicJoints(path);
  ASSERT_EQ(mimics.size(), 12u);
  for (const MimicJoint& m : mimics) {
    const bool left = m.name.rfind("gripper_left_", 0) == 0;
    EXPECT_EQ(m.leader, left ? "gripper_left_joint" : "gripper_right_joint") << m.name;
    EXPECT_TRUE(m.multiplier == 1.0 || m.multiplier == -1.0) << m.name;
    EXPECT_EQ(m.offset, 0.0) << m.name;
  }
  // For dynamics alone (no locked joints) the mimics are joints of their own: 44 revolute joints.
  EXPECT_EQ(buildModelFromUrdf(path, RootJoint::FreeFlyer).nv, 6 + 44);
  // For control (the robot loader, stride-init: locked joints, even none) they are refused.
  const std::map<std::string, double> none;
  try {
    buildModelFromUrdf(path, RootJoint::FreeFlyer, none);
    ADD_FAILURE() << "the full Talos loaded for control with its mimic joints as motors";
  } catch (const UrdfError& e) {
    const std::string msg = e.what();
    for (const char* fragment :
         {"talos_full_v2.urdf",
          "joint 'gripper_left_inner_double_joint' mimics "
          "'gripper_left_joint' (multiplier 1, offset 0)",
          "gripper_right_fingertip_3_joint", "Stride has no coupled joints",
          "lock 'gripper_left_joint', 'gripper_right_joint' (locked_joints)"})
      EXPECT_NE(msg.find(fragment), std::string::npos) << fragment << "\n" << msg;
  }
  // Grippers locked (closed, and half open): their 12 fingers follow. 44 revolute joints - 14.
  for (const double angle : {0.0, -0.5}) {
    const Model talos =
        buildModelFromUrdf(path, RootJoint::FreeFlyer,
                           {{"gripper_left_joint", angle}, {"gripper_right_joint", angle}});
    EXPECT_EQ(talos.nv, 6 + 30);
    EXPECT_EQ(talos.nq, 7 + 30);
    for (const MimicJoint& m : mimics) EXPECT_FALSE(talos.existJoint(m.name)) << m.name;
  }
  // The head locked as well.
  const Model still_head = buildModelFromUrdf(path, RootJoint::FreeFlyer,
                                              {{"gripper_left_joint", 0},
                                               {"gripper_right_joint", 0},
                                               {"head_1_joint", 0.1},
                                               {"head_2_joint", -0.2}});
  EXPECT_EQ(still_head.nv, 6 + 28);
  // The reduced Talos has its mimic tags on fixed joints: nothing to lock, it loads as before.
  EXPECT_TRUE(urdfMimicJoints(STRIDE_SHARED_DIR "/robots/talos/talos_reduced.urdf").empty());
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
  // Robots with mimic joints load with their leaders locked (the mimics follow).
  const std::vector<std::tuple<std::string, int, std::map<std::string, double>>> robots = {
      {"anymal/anymal.urdf", 18, {}},
      {"anymal_c/anymal.urdf", 18, {}},
      {"bolt/bolt.urdf", 12, {}},
      {"hyq/hyq_no_sensors.urdf", 18, {}},
      {"panda/panda.urdf", 13, {{"panda_finger_joint1", 0.02}}},
      {"solo12/solo.urdf", 14, {}},
      {"solo12/solo12.urdf", 18, {}},
      {"talos/talos_full_v2.urdf", 36, {{"gripper_left_joint", 0}, {"gripper_right_joint", 0}}},
      {"talos/talos_reduced.urdf", 38, {}},
      {"ur5/ur5_robot.urdf", 12, {}}};
  for (const auto& [file, nv, locked] : robots) {
    const Model model =
        buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/" + file, RootJoint::FreeFlyer, locked);
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

}  // namespace test_urdf
}  // namespace stride
