// The astronaut's reduced model (tools/paper/locked_model.hpp): locking joints by rewriting the
// URDF must give the same robot as the full model with those joints held at their default angles:
// same mass and CoM, same frame placements and velocities, same centroidal momentum (the locked
// bodies' inertia is folded into their parents, not lost).

#include <gtest/gtest.h>

#include <random>

#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "tools/paper/locked_model.hpp"

namespace stride {
namespace {

const std::string kHumanoid = STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml";
const std::vector<std::string> kSagittal = {"L_hip_pitch", "L_knee", "R_hip_pitch", "R_knee"};

TEST(LockedModel, OnlyTheFreeJointsMove) {
  const Robot robot = loadRobot(kHumanoid);
  const LockedRobot locked = lockJoints(robot, kSagittal);
  EXPECT_TRUE(locked.model.hasFreeFlyer());
  EXPECT_EQ(locked.model.nv, 6 + 4);
  EXPECT_EQ(locked.model.nq, 7 + 4);
  ASSERT_EQ(locked.free.size(), 4u);
  for (const auto& name : kSagittal) {
    const Joint& jr = locked.model.joints[locked.model.getJointId(name)];
    const Joint& jf = robot.model.joints[robot.model.getJointId(name)];
    EXPECT_TRUE(jr.axis.isApprox(jf.axis)) << name;
    EXPECT_EQ(locked.model.lowerPositionLimit[jr.idx_q], robot.model.lowerPositionLimit[jf.idx_q]);
    EXPECT_EQ(locked.model.upperPositionLimit[jr.idx_q], robot.model.upperPositionLimit[jf.idx_q]);
    EXPECT_EQ(locked.model.effortLimit[jr.idx_v], robot.model.effortLimit[jf.idx_v]);
  }
  EXPECT_THROW(lockJoints(robot, {"no_such_joint"}), std::invalid_argument);
  EXPECT_THROW(lockJointsInUrdf(robot.urdf_path, {{"no_such_joint", 0.0}}), std::invalid_argument);
}

TEST(LockedModel, MatchesTheFullModelAtTheSameConfiguration) {
  const Robot robot = loadRobot(kHumanoid);
  const LockedRobot locked = lockJoints(robot, kSagittal);
  const Model& full = robot.model;
  const Model& red = locked.model;
  EXPECT_NEAR(red.totalMass(), full.totalMass(), 1e-9);
  Data df(full), dr(red);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> rate(-3.0, 3.0);
  for (int trial = 0; trial < 5; ++trial) {
    // A random base pose and free-joint motion (within their limits); every locked joint at its
    // default angle, at rest.
    const Eigen::VectorXd qr = randomConfiguration(red, rng);
    Eigen::VectorXd vr(red.nv);
    for (int i = 0; i < red.nv; ++i) vr[i] = rate(rng);
    const Eigen::VectorXd q = expandConfiguration(full, red, qr, robot.default_q);
    const Eigen::VectorXd v = expandVelocity(full, red, vr);
    // The expansion keeps every locked joint at its default angle and at rest (the astronaut's
    // log draws the full robot so), and the reduction is its inverse.
    for (int i = 1; i < full.njoints(); ++i) {
      const Joint& jf = full.joints[i];
      if (jf.type == JointType::FreeFlyer || red.existJoint(jf.name)) continue;
      EXPECT_EQ(q[jf.idx_q], robot.default_q[jf.idx_q]) << jf.name;
      EXPECT_EQ(v[jf.idx_v], 0.0) << jf.name;
    }
    ASSERT_TRUE(reduceConfiguration(full, red, q).isApprox(qr));
    ASSERT_TRUE(reduceVelocity(full, red, v).isApprox(vr));

    const Vector6d hf = computeCentroidalMomentum(full, df, q, v);
    const Vector6d hr = computeCentroidalMomentum(red, dr, qr, vr);
    EXPECT_TRUE(dr.com.isApprox(df.com, 1e-9))
        << dr.com.transpose() << " vs " << df.com.transpose();
    EXPECT_LT((hr - hf).norm(), 1e-8 * (1.0 + hf.norm())) << hr.transpose() << "\n"
                                                          << hf.transpose();

    forwardKinematics(full, df, q, v);
    forwardKinematics(red, dr, qr, vr);
    updateFramePlacements(full, df);
    updateFramePlacements(red, dr);
    // Every link (a Body frame in both models, whatever became of its joint).
    int links = 0;
    for (int f = 1; f < red.nframes(); ++f) {
      if (red.frames[f].type != FrameType::Body) continue;
      const int ff = full.getFrameId(red.frames[f].name, FrameType::Body);
      EXPECT_TRUE(dr.oMf[f].isApprox(df.oMf[ff], 1e-9)) << red.frames[f].name;
      EXPECT_TRUE(getFrameVelocity(red, dr, f, ReferenceFrame::Local)
                      .isApprox(getFrameVelocity(full, df, ff, ReferenceFrame::Local), 1e-8))
          << red.frames[f].name;
      ++links;
    }
    int full_links = 0;
    for (const Frame& frame : full.frames) full_links += frame.type == FrameType::Body;
    EXPECT_EQ(links, full_links);
  }
}

}  // namespace
}  // namespace stride
