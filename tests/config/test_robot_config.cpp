// The in-house and the public robots load with the properties their issues asked for; robot files
// are found by path or package:// URI; bad YAML is reported with the file and the key.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "config/describe_model.hpp"
#include "config/model_hash.hpp"
#include "config/package_path.hpp"
#include "config/robot_config.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace test_robot_config {

namespace fs = std::filesystem;

const std::string kQuad = STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml";
const std::string kHumanoid = STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml";
// example-robot-data as a package (config/CMakeLists.txt); empty without ../shared.
const std::string kPackages = STRIDE_ROBOT_PACKAGES;

std::string robotYaml(const std::string& name) {
  return STRIDE_CONFIG_DIR "/robots/" + name + "/" + name + ".yaml";
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A directory per test (ctest runs the cases of this file in parallel processes), emptied when the
// test first asks for it.
std::string testDir() {
  static std::string emptied;
  const auto* info = testing::UnitTest::GetInstance()->current_test_info();
  const std::string name = std::string(info->test_suite_name()) + "." + info->name();
  const fs::path dir = fs::path(testing::TempDir()) / "stride_robot_config" / name;
  if (emptied != name) fs::remove_all(dir), emptied = name;
  fs::create_directories(dir);
  return dir.string();
}

std::string writeFile(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path) << text;
  return path;
}

// Sets (or unsets, with nullptr) an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    if (value)
      setenv(name, value, 1);
    else
      unsetenv(name);
  }
  ~ScopedEnv() {
    if (had_)
      setenv(name_.c_str(), old_.c_str(), 1);
    else
      unsetenv(name_.c_str());
  }

 private:
  std::string name_, old_;
  bool had_ = false;
};

// Contacts touch the ground (z = 0) in the default posture and the CoM projects inside the support
// polygon: the hull of the point feet and of the soles' corners, at least 1 cm inside.
void expectStandsOnTheGround(const Robot& robot) {
  Data data(robot.model);
  framesForwardKinematics(robot.model, data, robot.default_q);
  for (const auto& c : robot.contacts) {
    const SE3& oMf = data.oMf[robot.model.getFrameId(c.frame)];
    EXPECT_NEAR(oMf.p.z(), 0.0, 1e-6) << robot.name << " " << c.frame;
    // Flat within 2 mrad (talos' half_sitting rolls the ankles by 1.7 mrad).
    if (c.dim == 6) {
      EXPECT_LT(std::acos(std::min(1.0, oMf.R(2, 2))), 2e-3)
          << robot.name << " " << c.frame << " sole is not flat";
    }
  }
  EXPECT_GT(centerOfMass(robot.model, data, robot.default_q).z(), 0.1) << robot.name;
  EXPECT_LT(comOutsideSupport(robot, robot.default_q), -0.01)
      << robot.name << ": the CoM is not 1 cm inside the support polygon";
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

// Their YAMLs give exact base heights: loading them is silent.
TEST(RobotConfig, InHouseRobotsNeedNoBaseCorrection) {
  for (const auto& yaml : {kQuad, kHumanoid}) {
    testing::internal::CaptureStderr();
    const Robot robot = loadRobot(yaml);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << yaml;
  }
}

// ---- the public robots (example-robot-data), by their package:// URIs ----

struct PublicRobot {
  const char* name;
  int nv;
  std::vector<const char*> feet;
  int dim;
  const char* posture;
};

const std::vector<PublicRobot> kPublicRobots = {
    {"solo12", 18, {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"}, 3, "standing"},
    {"anymal_c", 18, {"LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"}, 3, "standing"},
    {"talos_reduced", 38, {"left_sole_link", "right_sole_link"}, 6, "half_sitting"},
};

void expectPublicRobot(const Robot& robot, const PublicRobot& expected) {
  EXPECT_EQ(robot.name, expected.name);
  EXPECT_EQ(robot.model.nv, expected.nv);
  EXPECT_EQ(robot.model.nq, expected.nv + 1);
  ASSERT_EQ(robot.contacts.size(), expected.feet.size());
  for (std::size_t k = 0; k < expected.feet.size(); ++k) {
    EXPECT_EQ(robot.contacts[k].frame, expected.feet[k]);
    EXPECT_EQ(robot.contacts[k].dim, expected.dim);
  }
  EXPECT_EQ(robot.reference_posture, expected.posture);
  expectStandsOnTheGround(robot);
}

TEST(RobotConfig, PublicRobotsThroughRobotsDir) {
  ASSERT_FALSE(kPackages.empty()) << "no ../shared/robots/SOURCES.md: no package view";
  const ScopedEnv no_ros("ROS_PACKAGE_PATH", nullptr);
  for (const auto& expected : kPublicRobots) {
    testing::internal::CaptureStderr();
    const Robot robot = loadRobot(robotYaml(expected.name), {kPackages});
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "")
        << expected.name << ": our YAML's base height should put the feet on the ground";
    EXPECT_EQ(robot.urdf_path.rfind(kPackages + "/example-robot-data/robots/", 0), 0u)
        << robot.urdf_path;
    expectPublicRobot(robot, expected);
  }
  // Torque limits: solo12's YAML replaces the URDF's placeholder 1000 N m; the others keep the
  // URDF's efforts.
  const Robot solo = loadRobot(robotYaml("solo12"), {kPackages});
  EXPECT_TRUE((solo.model.effortLimit.tail(12).array() == 2.7).all());
  const Robot anymal = loadRobot(robotYaml("anymal_c"), {kPackages});
  EXPECT_TRUE((anymal.model.effortLimit.tail(12).array() == 80.0).all());
  const Robot talos = loadRobot(robotYaml("talos_reduced"), {kPackages});
  const Model& m = talos.model;
  EXPECT_DOUBLE_EQ(m.effortLimit[m.joints[m.getJointId("leg_left_4_joint")].idx_v], 300.0);
  EXPECT_DOUBLE_EQ(m.effortLimit[m.joints[m.getJointId("leg_left_6_joint")].idx_v], 100.0);
  // The SRDF's half_sitting, except the base height.
  const Eigen::VectorXd& half_sitting = m.referenceConfigurations.at("half_sitting");
  EXPECT_TRUE(talos.default_q.tail(m.nq - 3).isApprox(half_sitting.tail(m.nq - 3), 1e-12));
}

TEST(RobotConfig, PublicRobotsThroughRosPackagePath) {
  ASSERT_FALSE(kPackages.empty()) << "no ../shared/robots/SOURCES.md: no package view";
  // An entry that does not hold the package comes first: the search goes on to the next.
  const std::string path = "/nonexistent/stride:" + kPackages + ":";
  const ScopedEnv ros("ROS_PACKAGE_PATH", path.c_str());
  for (const auto& expected : kPublicRobots) {
    const Robot robot = loadRobot(robotYaml(expected.name));
    expectPublicRobot(robot, expected);
    EXPECT_EQ(robot.default_q, loadRobot(robotYaml(expected.name), {kPackages}).default_q);
  }
}

TEST(RobotConfig, PublicRobotWithoutPackageSaysWhereItLooked) {
  const ScopedEnv no_ros("ROS_PACKAGE_PATH", nullptr);
  const std::string empty = testDir();
  try {
    loadRobot(robotYaml("solo12"), {empty});
    FAIL() << "found a package in an empty directory";
  } catch (const RobotFileNotFound& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("solo12.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("urdf"), std::string::npos) << what;
    EXPECT_NE(what.find("package://example-robot-data/robots/solo_description/robots/solo12.urdf"),
              std::string::npos)
        << what;
    EXPECT_EQ(e.tried().size(), 2u);
    for (const auto& t : e.tried()) EXPECT_NE(what.find(t), std::string::npos) << what;
  }
}

// ---- the resolver ----

TEST(PackagePath, EveryLayoutAndOrder) {
  const ScopedEnv no_ros("ROS_PACKAGE_PATH", nullptr);
  const std::string root = testDir();
  const std::string uri = "package://mypkg/robots/r.urdf";
  // D/NAME/REST, D/REST with D = .../NAME, D/share/NAME/REST.
  const std::string a = root + "/a", b = root + "/b/mypkg", c = root + "/c";
  const std::string in_a = writeFile(a + "/mypkg/robots/r.urdf", "a");
  const std::string in_b = writeFile(b + "/robots/r.urdf", "b");
  const std::string in_c = writeFile(c + "/share/mypkg/robots/r.urdf", "c");
  EXPECT_EQ(resolveRobotFile(uri, "", {a}), in_a);
  EXPECT_EQ(resolveRobotFile(uri, "", {b}), in_b);
  EXPECT_EQ(readFile(resolveRobotFile(uri, "", {b + "/"})), "b");
  EXPECT_EQ(resolveRobotFile(uri, "", {c}), in_c);
  // The first directory that has it wins.
  EXPECT_EQ(resolveRobotFile(uri, "", {root, c, a}), in_c);
  // ROS_PACKAGE_PATH after the program's directories.
  {
    const std::string path = root + ":" + a;
    const ScopedEnv ros("ROS_PACKAGE_PATH", path.c_str());
    EXPECT_EQ(resolveRobotFile(uri, "", {}), in_a);
    EXPECT_EQ(resolveRobotFile(uri, "", {c}), in_c);
  }
  // Paths: relative to the YAML's directory, absolute, file://.
  EXPECT_EQ(readFile(resolveRobotFile("robots/r.urdf", b, {})), "b");
  EXPECT_EQ(resolveRobotFile(in_c, b, {}), in_c);
  EXPECT_EQ(resolveRobotFile("file://" + in_c, b, {}), in_c);
  EXPECT_THROW(resolveRobotFile("robots/missing.urdf", b, {}), RobotFileNotFound);
  EXPECT_THROW(resolveRobotFile("package://mypkg", "", {a}), ConfigError);
  EXPECT_THROW(resolveRobotFile("package:///robots/r.urdf", "", {a}), ConfigError);
}

TEST(PackagePath, MissingPackageListsEveryPlaceLooked) {
  const std::string root = testDir();
  const std::string a = root + "/a", named = root + "/d/other", env = root + "/e";
  const std::string path = env + "::";
  const ScopedEnv ros("ROS_PACKAGE_PATH", path.c_str());
  try {
    resolveRobotFile("package://other/x.urdf", "", {a, named});
    FAIL() << "resolved a missing package";
  } catch (const RobotFileNotFound& e) {
    const std::vector<std::string> expected = {
        a + "/other/x.urdf",        a + "/share/other/x.urdf",     named + "/other/x.urdf",
        named + "/x.urdf",          named + "/share/other/x.urdf", env + "/other/x.urdf",
        env + "/share/other/x.urdf"};
    EXPECT_EQ(e.tried(), expected);
    const std::string what = e.what();
    for (const auto& t : expected) EXPECT_NE(what.find(t), std::string::npos) << what;
    EXPECT_NE(what.find("package://other/x.urdf"), std::string::npos) << what;
    EXPECT_NE(what.find("ROS_PACKAGE_PATH"), std::string::npos) << what;
    EXPECT_NE(what.find("--robots-dir"), std::string::npos) << what;
  }
  const ScopedEnv no_ros("ROS_PACKAGE_PATH", nullptr);
  try {
    resolveRobotFile("package://other/x.urdf", "", {});
    FAIL() << "resolved a package with nowhere to look";
  } catch (const RobotFileNotFound& e) {
    EXPECT_TRUE(e.tried().empty());
    EXPECT_NE(std::string(e.what()).find("ROS_PACKAGE_PATH"), std::string::npos) << e.what();
  }
}

// ---- YAML variants, written into a temporary directory ----

const std::string kQuadUrdfLine = "urdf: stride_quad.urdf";
const std::string kQuadUrdfAbsolute =
    "urdf: " STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.urdf";
const std::string kQuadBase = "  base: [0.0, 0.0, 0.222946147, 0.0, 0.0, 0.0, 1.0]\n";

// The in-house quadruped's YAML, its URDF named by absolute path so that the copy can live
// anywhere.
std::string quadText() {
  std::string s = readFile(kQuad);
  const auto pos = s.find(kQuadUrdfLine);
  EXPECT_NE(pos, std::string::npos);
  return s.replace(pos, kQuadUrdfLine.size(), kQuadUrdfAbsolute);
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return pos == std::string::npos ? s : s.replace(pos, from.size(), to);
}

// The YAML's error, or "" when it loads.
std::string loadError(const std::string& yaml, const std::vector<std::string>& robots_dirs = {}) {
  const std::string path = writeFile(testDir() + "/test_broken.yaml", yaml);
  try {
    loadRobot(path, robots_dirs);
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("test_broken.yaml"), std::string::npos) << what;
    return what;
  }
  return "";
}

void expectConfigError(const std::string& yaml, const std::string& fragment) {
  const std::string what = loadError(yaml);
  EXPECT_NE(what.find(fragment), std::string::npos)
      << (what.empty() ? "accepted" : what) << "; expected an error with '" << fragment << "'";
}

TEST(RobotConfig, BadInput) {
  EXPECT_THROW(loadRobot("/nonexistent.yaml"), ConfigError);
  const std::string good = quadText();
  auto with = [&](const std::string& from, const std::string& to) {
    return replaced(good, from, to);
  };
  EXPECT_EQ(loadError(good), "");
  expectConfigError("name: [unclosed", "malformed YAML");
  expectConfigError(with("name: stride_quad", "nom: stride_quad"), "unknown key 'nom'");
  expectConfigError(with("name: stride_quad\n", ""), "missing key 'name'");
  expectConfigError(with("{frame: FL_foot, dim: 3}", "{frame: FL_toe, dim: 3}"),
                    "contact frame 'FL_toe'");
  expectConfigError(with("{frame: FL_foot, dim: 3}", "{frame: FL_foot, dim: 4}"), "dim 4");
  expectConfigError(with("{frame: FR_foot, dim: 3}", "{frame: FL_foot, dim: 3}"), "listed twice");
  expectConfigError(with("FL_HAA: 2.7,", "FL_HAA: -1,"), "must be positive");
  expectConfigError(with("FL_HAA: 2.7,", "FL_HAA: .inf,"), "must be positive and finite");
  expectConfigError(with("FL_HAA: 2.7,", "FL_HAA: 2.7, FL_toe: 1,"), "joint 'FL_toe'");
  expectConfigError(with("FL_HAA: 2.7,", "root_joint: 2.7,"), "not actuated");
  expectConfigError(with("FL_HAA: 0.0,", ""),
                    "default_posture.joints has no entry for joint 'FL_HAA'");
  expectConfigError(with(kQuadBase, ""), "missing key 'base'");
  expectConfigError(with("default_posture:", "posture:"), "unknown key 'posture'");
  expectConfigError(with(kQuadUrdfAbsolute, "urdf: missing.urdf"), "does not exist");
  expectConfigError(with("root_joint: free-flyer", "root_joint: planar"), "root_joint must be");
  expectConfigError(with("0.0, 0.0, 0.0, 1.0]", "0.0, 0.0, 0.5, 1.0]"), "quaternion is not unit");
  expectConfigError(good + "reference_posture: standing\n", "reference_posture needs an 'srdf'");
  const std::string pd = "joint_pd: {kp: 20.0, kd: 0.3}";
  expectConfigError(with(pd, "joint_pd: {kp: -1, kd: 0.3}"), "kp must be positive");
  expectConfigError(with(pd, "joint_pd: {kp: .nan, kd: 0.3}"), "kp must be positive");
  expectConfigError(with(pd, "joint_pd: {kp: 20.0}"), "missing key 'kd'");
  expectConfigError(with(pd, "joint_pd: {kp: 20.0, kd: 0.3, ki: 1}"), "unknown key 'joint_pd.ki'");
  const std::string path = writeFile(testDir() + "/test_pd.yaml", good);
  const Robot quad = loadRobot(path);
  EXPECT_EQ(quad.joint_kp, 20.0);
  EXPECT_EQ(quad.joint_kd, 0.3);
  EXPECT_EQ(loadRobot(writeFile(testDir() + "/test_pd.yaml", with(pd, ""))).joint_kp, 0.0);
}

// The error of the humanoid's YAML changed to `text` (beside its URDF), or "" when it loads.
std::string humanoidError(const std::string& text) {
  const std::string path = writeFile(testDir() + "/humanoid/stride_humanoid.yaml", text);
  fs::copy(fs::path(kHumanoid).parent_path() / "stride_humanoid.urdf",
           fs::path(path).parent_path() / "stride_humanoid.urdf",
           fs::copy_options::overwrite_existing);
  try {
    loadRobot(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// What would load and run but mean something else (issue 34) is refused, saying what is right.
TEST(RobotConfig, FeetInAnotherOrderThanTheGaitsAssume) {
  // HyQ's lf, lh, rf, rh: a pace became a bound. Here the quadruped's FR and HL swapped.
  const std::string swapped =
      replaced(replaced(quadText(), "{frame: FR_foot, dim: 3}", "{frame: @, dim: 3}"),
               "{frame: HL_foot, dim: 3}", "{frame: FR_foot, dim: 3}");
  const std::string error =
      loadError(replaced(swapped, "{frame: @, dim: 3}", "{frame: HL_foot, dim: 3}"));
  for (const char* part :
       {"contacts are not in the order the gaits assume (front-left, front-right, hind-left, "
        "hind-right)",
        "contacts[1] 'HL_foot' at (x -", "is hind-left", "contacts[2] 'FR_foot' at (x 0.",
        "is front-right", "List them as: FL_foot, FR_foot, HL_foot, HR_foot"})
    EXPECT_NE(error.find(part), std::string::npos) << error;
  // A biped: left, then right.
  std::string humanoid = readFile(kHumanoid);
  humanoid = replaced(replaced(humanoid, "{frame: L_sole, dim: 6}", "{frame: @, dim: 6}"),
                      "{frame: R_sole, dim: 6}", "{frame: L_sole, dim: 6}");
  humanoid = replaced(humanoid, "{frame: @, dim: 6}", "{frame: R_sole, dim: 6}");
  const std::string w = humanoidError(humanoid);
  for (const char* part :
       {"(left, right)", "'R_sole' at (x", "is right", "List them as: L_sole, R_sole"})
    EXPECT_NE(w.find(part), std::string::npos) << w;
}

TEST(RobotConfig, AJointIsNotAContactFrame) {
  expectConfigError(replaced(quadText(), "{frame: FL_foot, dim: 3}", "{frame: FL_KFE, dim: 3}"),
                    "contacts[0].frame: 'FL_KFE' is a joint (its frame is on the joint's axis, not "
                    "at the foot); name the foot's link or frame instead (the frames this joint "
                    "moves: ");
  const std::string what =
      loadError(replaced(quadText(), "{frame: FL_foot, dim: 3}", "{frame: FL_KFE, dim: 3}"));
  EXPECT_NE(what.find("FL_foot"), std::string::npos) << what << ": the foot's frame is suggested";
}

TEST(RobotConfig, AFlatSoleNeedsItsExtents) {
  std::string humanoid = readFile(kHumanoid);
  humanoid = replaced(humanoid, "sole_half_extents: [0.11, 0.065]\n", "");
  EXPECT_NE(humanoidError(humanoid).find(
                "contacts[0] 'L_sole' has dim 6 (a flat sole) but 'sole_half_extents' is not "
                "given: the sole's half length and half width [m]"),
            std::string::npos);
}

// Bolt's SRDF posture puts its centre of mass 1.9 cm behind its point feet: a warning with the
// distance; hips straighter, 6.5 cm: refused.
TEST(RobotConfig, ACentreOfMassOutsideTheFeetIsSaid) {
  ASSERT_FALSE(kPackages.empty()) << "no ../shared/robots/SOURCES.md: no package view";
  const std::string bolt =
      "name: bolt\n"
      "urdf: package://example-robot-data/robots/bolt_description/robots/bolt.urdf\n"
      "srdf: package://example-robot-data/robots/bolt_description/srdf/bolt.srdf\n"
      "reference_posture: standing\n"
      "root_joint: free-flyer\n"
      "contacts:\n  - {frame: FL_FOOT, dim: 3}\n  - {frame: FR_FOOT, dim: 3}\n";
  const std::string path = writeFile(testDir() + "/bolt.yaml", bolt);
  testing::internal::CaptureStderr();
  const Robot robot = loadRobot(path, {kPackages});
  const std::string warning = testing::internal::GetCapturedStderr();
  for (const char* part : {"warning: robot config", "bolt.yaml",
                           "the default posture's centre of mass is 1.9 cm outside the support "
                           "polygon of its two point feet (a line) (1.9 cm behind"})
    EXPECT_NE(warning.find(part), std::string::npos) << warning;
  EXPECT_NEAR(comOutsideSupport(robot, robot.default_q), 0.019, 0.0005);
  const std::string error =
      loadError(bolt + "default_posture:\n  joints: {FL_HFE: 0.6, FR_HFE: 0.6}\n", {kPackages});
  EXPECT_NE(error.find("centre of mass is 6.5 cm outside the support polygon"), std::string::npos)
      << error;
  EXPECT_NE(error.find("(more than 5 cm: refused)"), std::string::npos) << error;
  // The shipped robots stand 1 cm inside (expectStandsOnTheGround), without a word.
  testing::internal::CaptureStderr();
  loadRobot(kQuad);
  loadRobot(kHumanoid);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

// Full TALOS: 12 gripper joints <mimic> the two gripper joints. Unlocked, refused with what to
// lock; locked, the grippers are no motors and the rest is talos_reduced's legs and arms.
TEST(RobotConfig, LockedJointsAndMimicJoints) {
  ASSERT_FALSE(kPackages.empty()) << "no ../shared/robots/SOURCES.md: no package view";
  std::string full = readFile(robotYaml("talos_reduced"));
  full = replaced(full, "talos_reduced.urdf", "talos_full_v2.urdf");
  full = replaced(full, "name: talos_reduced", "name: talos_full");
  const std::string what = loadError(full, {kPackages});
  for (const char* part :
       {"mimics 'gripper_left_joint'", "lock 'gripper_left_joint'", "locked_joints"})
    EXPECT_NE(what.find(part), std::string::npos) << what;
  const std::string locked =
      full + "locked_joints: {gripper_left_joint: 0.0, gripper_right_joint: 0.0}\n";
  const Robot talos = loadRobot(writeFile(testDir() + "/talos_full.yaml", locked), {kPackages});
  EXPECT_EQ(talos.model.nv, 36);
  EXPECT_FALSE(talos.model.existJoint("gripper_left_joint"));
  EXPECT_FALSE(talos.model.existJoint("gripper_left_inner_double_joint"));
  expectStandsOnTheGround(talos);
  EXPECT_NE(loadError(full + "locked_joints: {gripper_left_joint: 0.0, no_such_joint: 0.0}\n",
                      {kPackages})
                .find("no_such_joint"),
            std::string::npos);
  expectConfigError(quadText() + "locked_joints: [FL_HAA]\n", "locked_joints must be a map");
  // A quadruped with a leg's abduction locked: one motor fewer.
  const Robot quad =
      loadRobot(writeFile(testDir() + "/locked_quad.yaml",
                          replaced(replaced(quadText(), "FL_HAA: 0.0, ", ""), "FL_HAA: 2.7, ", "") +
                              "locked_joints: {FL_HAA: 0.0}\n"));
  EXPECT_EQ(quad.model.nv, 17);
}

// A misspelt key would otherwise silently leave its default in place.
TEST(RobotConfig, UnknownKeysAtEveryLevel) {
  const std::string good = quadText();
  expectConfigError(replaced(good, "contacts:", "contcts:"), "unknown key 'contcts'");
  expectConfigError(good + "sole_half_extent: [0.1, 0.05]\n", "unknown key 'sole_half_extent'");
  expectConfigError(replaced(good, "{frame: HL_foot, dim: 3}", "{frame: HL_foot, dim: 3, mu: 1}"),
                    "unknown key 'contacts[2].mu'");
  expectConfigError(replaced(good, "  joints: {", "  jionts: {"),
                    "unknown key 'default_posture.jionts'");
  expectConfigError(replaced(good, "  base:", "  bse:"), "unknown key 'default_posture.bse'");
}

TEST(RobotConfig, TorqueLimits) {
  const std::string good = quadText();
  const std::string limits = good.substr(
      good.find("torque_limits:"), good.find("default_posture:") - good.find("torque_limits:"));
  const std::string dir = testDir();
  auto load = [&](const std::string& text) {
    return loadRobot(writeFile(dir + "/quad.yaml", text)).model.effortLimit;
  };
  // One number for every joint.
  const Eigen::VectorXd scalar = load(replaced(good, limits, "torque_limits: 1.5\n"));
  EXPECT_TRUE((scalar.tail(12).array() == 1.5).all()) << scalar.transpose();
  // A map: the joints it names; the others keep the URDF's effort (2.7).
  const Eigen::VectorXd map = load(replaced(good, limits, "torque_limits: {FL_KFE: 4.0}\n"));
  const Model quad = loadRobot(kQuad).model;
  EXPECT_EQ(map[quad.joints[quad.getJointId("FL_KFE")].idx_v], 4.0);
  EXPECT_EQ((map.tail(12).array() == 2.7).count(), 11);
  // None: the URDF's efforts.
  const Eigen::VectorXd urdf = load(replaced(good, limits, ""));
  EXPECT_TRUE((urdf.tail(12).array() == 2.7).all()) << urdf.transpose();
  expectConfigError(replaced(good, limits, "torque_limits: 0\n"), "must be positive");
  expectConfigError(replaced(good, limits, "torque_limits: [1, 2]\n"), "torque_limits must be");

  // A URDF with a zero effort for `b` (urdfdom requires the attribute): its limit must come from
  // the YAML.
  const std::string arm = writeFile(dir + "/arm.urdf", R"(<robot name="arm">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="l1"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="l2"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <joint name="a" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="5" velocity="1"/></joint>
  <joint name="b" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/>
    <origin xyz="0 0 0.5"/><limit lower="-1" upper="1" effort="0" velocity="1"/></joint>
</robot>
)");
  const std::string arm_yaml = "name: arm\nurdf: " + arm +
                               "\nroot_joint: fixed\ncontacts: []\n"
                               "default_posture: {joints: {a: 0.1, b: 0.2}}\n";
  expectConfigError(arm_yaml, "joint 'b' has no torque limit");
  const Robot fixed = loadRobot(writeFile(dir + "/arm.yaml", arm_yaml + "torque_limits: {b: 3}\n"));
  EXPECT_EQ(fixed.model.effortLimit, Eigen::Vector2d(5, 3));
  EXPECT_EQ(fixed.default_q, Eigen::Vector2d(0.1, 0.2));
  // A fixed base: q, v and u are the joints.
  const std::string text = describeModel(fixed);
  for (const char* part : {"fixed base", "nq 2, nv 2, nu 2", "q[1]     b", "u[0]     a"})
    EXPECT_NE(text.find(part), std::string::npos) << part << " in\n" << text;
  EXPECT_EQ(text.find("root_joint"), std::string::npos) << text;
  expectConfigError(replaced(arm_yaml, "b: 0.2}", "b: 0.2}, base: [0, 0, 0, 0, 0, 0, 1]") +
                        "torque_limits: {b: 3}\n",
                    "only for a free-flyer");
}

// ---- the default posture from an SRDF group_state ----

const std::string kSoloHeader =
    "name: solo_test\n"
    "urdf: package://example-robot-data/robots/solo_description/robots/solo12.urdf\n"
    "srdf: package://example-robot-data/robots/solo_description/srdf/solo.srdf\n"
    "root_joint: free-flyer\n"
    "contacts: [{frame: FL_FOOT, dim: 3}, {frame: FR_FOOT, dim: 3}, {frame: HL_FOOT, dim: 3},\n"
    "           {frame: HR_FOOT, dim: 3}]\n"
    "torque_limits: 2.7\n";

TEST(RobotConfig, SrdfPostureWithYamlOverrides) {
  ASSERT_FALSE(kPackages.empty()) << "no ../shared/robots/SOURCES.md: no package view";
  const std::string dir = testDir();
  const std::string yaml =
      writeFile(dir + "/solo.yaml", kSoloHeader +
                                        "reference_posture: standing\n"
                                        "default_posture:\n"
                                        "  joints: {FL_HAA: 0.0, HR_KFE: 1.5}\n");
  testing::internal::CaptureStderr();
  const Robot robot = loadRobot(yaml, {kPackages});
  const std::string warning = testing::internal::GetCapturedStderr();
  const Model& m = robot.model;
  const Eigen::VectorXd& standing = m.referenceConfigurations.at("standing");
  auto q = [&](const Eigen::VectorXd& x, const char* joint) {
    return x[m.joints[m.getJointId(joint)].idx_q];
  };
  EXPECT_EQ(q(robot.default_q, "FL_HAA"), 0.0);
  EXPECT_EQ(q(robot.default_q, "HR_KFE"), 1.5);
  for (const char* j : {"FR_HAA", "FL_HFE", "FL_KFE", "HL_HAA", "HR_HAA", "HR_HFE"})
    EXPECT_EQ(q(robot.default_q, j), q(standing, j)) << j;
  EXPECT_EQ(robot.default_q.segment<2>(0), standing.segment<2>(0));
  EXPECT_EQ(robot.default_q.segment<4>(3), standing.segment<4>(3));
  // The SRDF's height is not the one that puts the feet on the ground: computed, and said. With a
  // knee bent differently, only the lowest foot touches.
  EXPECT_NE(warning.find("solo.yaml"), std::string::npos) << warning;
  Data data(m);
  framesForwardKinematics(m, data, robot.default_q);
  double lowest = 1.0;
  for (const auto& c : robot.contacts)
    lowest = std::min(lowest, data.oMf[m.getFrameId(c.frame)].p.z());
  EXPECT_NEAR(lowest, 0.0, 1e-12);

  // The YAML's base replaces the SRDF's, but its height is computed as well.
  const std::string based =
      writeFile(dir + "/based.yaml", kSoloHeader +
                                         "reference_posture: straight_standing\n"
                                         "default_posture: {base: [0.1, -0.2, 0.3, 0, 0, 0, 1]}\n");
  testing::internal::CaptureStderr();
  const Robot moved = loadRobot(based, {kPackages});
  testing::internal::GetCapturedStderr();
  EXPECT_EQ(moved.default_q.segment<2>(0), Eigen::Vector2d(0.1, -0.2));
  EXPECT_EQ(moved.default_q.tail(12), m.referenceConfigurations.at("straight_standing").tail(12));
  expectStandsOnTheGround(moved);

  // An SRDF state the file does not have: the error names the key and the states it has.
  const std::string what = loadError(kSoloHeader + "reference_posture: sitting\n", {kPackages});
  for (const char* part :
       {"reference_posture 'sitting'", "solo.srdf", "standing", "straight_standing"})
    EXPECT_NE(what.find(part), std::string::npos) << what;
}

TEST(RobotConfig, BaseHeightWarning) {
  const std::string dir = testDir();
  const std::string yaml = writeFile(
      dir + "/high_quad.yaml", replaced(quadText(), "[0.0, 0.0, 0.222946147,", "[0.0, 0.0, 0.25,"));
  testing::internal::CaptureStderr();
  const Robot robot = loadRobot(yaml);
  const std::string warning = testing::internal::GetCapturedStderr();
  for (const char* part : {"warning", "high_quad.yaml", "0.2500", "0.2229", "2.7 cm above"})
    EXPECT_NE(warning.find(part), std::string::npos) << warning;
  EXPECT_NEAR(robot.default_q[2], 0.222946147, 1e-8);
  EXPECT_EQ(robot.model.referenceConfigurations.at("default"), robot.default_q);
  expectStandsOnTheGround(robot);
  // Within a millimetre: corrected silently.
  testing::internal::CaptureStderr();
  loadRobot(writeFile(dir + "/close_quad.yaml", replaced(quadText(), "0.222946147,", "0.2235,")));
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

// ---- the model in wire order ----

// The wire contract's hash tells apart robots whose messages have the same sizes (an ANYmal
// controller must refuse a Solo-12's states), and only what changes the meaning of an index
// changes it.
TEST(ModelHash, TellsRobotsOfTheSameSizesApart) {
  const Robot quad = loadRobot(kQuad);
  const Robot solo = loadRobot(robotYaml("solo12"), {kPackages});
  const Robot anymal = loadRobot(robotYaml("anymal_c"), {kPackages});
  ASSERT_EQ(quad.model.nq, solo.model.nq);
  ASSERT_EQ(solo.model.nq, anymal.model.nq);
  EXPECT_NE(modelHash(solo), modelHash(anymal));
  EXPECT_NE(modelHash(quad), modelHash(anymal));
  EXPECT_EQ(modelHash(anymal), modelHash(loadRobot(robotYaml("anymal_c"), {kPackages})));
  EXPECT_NE(modelHash(loadRobot(kHumanoid)), modelHash(quad));
  // Pinned: estimators in the field carry this number; a change to the hash's definition (or to
  // the joint type names it reads, toString(JointType)) must be a decision, not an accident.
  EXPECT_EQ(static_cast<std::uint64_t>(modelHash(quad)), 0xea5842469bb5543aULL);

  Robot changed = quad;  // the contacts in another order: the phase bits mean other feet
  std::swap(changed.contacts[0], changed.contacts[1]);
  EXPECT_NE(modelHash(changed), modelHash(quad));
  changed = quad;  // a joint renamed
  changed.model.joints[2].name += "_2";
  EXPECT_NE(modelHash(changed), modelHash(quad));
  changed = quad;  // a revolute joint made prismatic
  changed.model.joints[2].type = JointType::Prismatic;
  EXPECT_NE(modelHash(changed), modelHash(quad));
  changed = quad;  // masses and limits retuned: the same wire
  changed.model.effortLimit *= 2.0;
  changed.model.inertias[3].m *= 1.5;
  changed.name = "retuned";
  EXPECT_EQ(modelHash(changed), modelHash(quad));
  changed = quad;  // a shank 1 cm longer: another robot (issue 34)
  changed.model.joints[3].placement.p.z() -= 0.01;
  EXPECT_NE(modelHash(changed), modelHash(quad));
  changed = quad;  // a joint's axis the other way
  changed.model.joints[2].axis = -changed.model.joints[2].axis;
  EXPECT_NE(modelHash(changed), modelHash(quad));
  changed = quad;  // a foot frame moved
  changed.model.frames[changed.model.getFrameId(quad.contacts[0].frame)].placement.p.x() += 0.01;
  EXPECT_NE(modelHash(changed), modelHash(quad));
  changed = quad;  // a placement that differs in its last bits (another parser or compiler)
  changed.model.joints[3].placement.p.z() += 1e-12;
  changed.model.joints[3].placement.R(0, 1) += 1e-12;
  EXPECT_EQ(modelHash(changed), modelHash(quad));

  // ANYmal B and ANYmal C: the same joint names, types and order and the same foot names; other
  // legs (issue 34: a B controller took a C robot's states).
  const Robot anymal_c = loadRobot(robotYaml("anymal_c"), {kPackages});
  Robot anymal_b = anymal_c;
  anymal_b.model = buildModelFromUrdf(
      kPackages + "/example-robot-data/robots/anymal_b_simple_description/robots/anymal.urdf",
      RootJoint::FreeFlyer);
  const std::vector<WireJoint> b_joints = wireJoints(anymal_b.model),
                               c_joints = wireJoints(anymal_c.model);
  ASSERT_EQ(b_joints.size(), c_joints.size());
  for (std::size_t i = 0; i < b_joints.size(); ++i) {
    EXPECT_EQ(b_joints[i].name, c_joints[i].name);
    EXPECT_EQ(b_joints[i].type, c_joints[i].type);
  }
  for (const ContactSpec& c : anymal_c.contacts)
    EXPECT_NO_THROW(anymal_b.model.getFrameId(c.frame)) << c.frame;
  EXPECT_NE(modelHash(anymal_b), modelHash(anymal_c));

  const std::vector<WireJoint> joints = wireJoints(quad.model);
  ASSERT_EQ(joints.size(), 13u);
  EXPECT_EQ(joints[0].type, "free-flyer");
  EXPECT_EQ(joints[0].idx_q, 0);
  EXPECT_EQ(joints[1].type, "revolute");
  EXPECT_EQ(joints[1].idx_q, 7);
  EXPECT_EQ(joints[1].idx_v, 6);
  EXPECT_EQ(joints[12].idx_q, 18);
  // --print-model shows it.
  char hex[17];
  std::uint64_t u;
  const std::int64_t h = modelHash(quad);
  std::memcpy(&u, &h, 8);
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(u));
  EXPECT_NE(describeModel(quad).find("model hash " + std::string(hex) + " (int64 " +
                                     std::to_string(h) + ";"),
            std::string::npos)
      << describeModel(quad);
}

TEST(RobotConfig, DescribeModel) {
  const Robot robot = loadRobot(kQuad);
  const std::string text = describeModel(robot);
  for (const char* part :
       {"stride_quad", "stride_quad.yaml", "stride_quad.urdf", "nq 19", "nv 18", "nu 12", "kg",
        "base height 0.2229", "q[0:7]", "v[0:6]", "x y z qx qy qz qw"})
    EXPECT_NE(text.find(part), std::string::npos) << part << " in\n" << text;
  // Each section lists every joint in the model's order, at its index.
  const Model& m = robot.model;
  for (const char* section :
       {"q, configuration", "v, velocity", "u, joint torques", "actuated joints"}) {
    std::size_t at = text.find(section);
    ASSERT_NE(at, std::string::npos) << section;
    for (int i = 2; i < m.njoints(); ++i) {
      const Joint& j = m.joints[i];
      const std::string index = section[0] == 'q'   ? "q[" + std::to_string(j.idx_q) + "]"
                                : section[0] == 'v' ? "v[" + std::to_string(j.idx_v) + "]"
                                                    : "u[" + std::to_string(j.idx_v - 6) + "]";
      const std::size_t found = text.find(index, at);
      ASSERT_NE(found, std::string::npos) << section << " " << j.name << "\n" << text;
      EXPECT_EQ(text.find(j.name, found), text.find_first_not_of(" ", found + index.size()))
          << section << " " << j.name << "\n"
          << text;
      at = found + index.size();
    }
  }
  std::size_t at = text.find("contacts (4)");
  ASSERT_NE(at, std::string::npos) << text;
  for (const auto& c : robot.contacts) {
    at = text.find(c.frame, at);
    ASSERT_NE(at, std::string::npos) << c.frame << "\n" << text;
    EXPECT_NE(text.find("dim 3", at), std::string::npos);
  }
  EXPECT_NE(text.find("2.70 N m"), std::string::npos) << text;
  EXPECT_NE(text.find("-1.6000 rad"), std::string::npos) << text;
}

}  // namespace test_robot_config
}  // namespace stride
