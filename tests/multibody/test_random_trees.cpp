// The dynamics identities of test_dynamics (random_tree.hpp, namespace checks) on 30 random
// kinematic trees: 1 to 25 one-dof joints, with and without a free-flyer root, aligned and
// unaligned revolute axes, prismatic joints, offset and merged bodies, operational frames. Fixed
// seeds: every run checks the same trees.

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "multibody/random_tree.hpp"

namespace stride {
namespace test_random_trees {

struct TreeCase {
  std::string name;
  Model model;
  std::vector<checks::Sample> samples;
};

constexpr int kTrees = 30;

const std::vector<TreeCase>& trees() {
  static const std::vector<TreeCase> all = [] {
    std::vector<TreeCase> out;
    for (int k = 0; k < kTrees; ++k) {
      std::mt19937 rng(1000 + k);
      const int n = 1 + (k * 24) / (kTrees - 1);  // 1 .. 25 joints
      const bool ff = k % 2 == 1;
      TreeCase c;
      c.name = "tree " + std::to_string(k) + " (" + std::to_string(n) + " joints" +
               (ff ? ", free-flyer)" : ", fixed base)");
      c.model = makeRandomTree(rng, n, ff);
      c.samples = checks::randomSamples(c.model, rng, 3);
      out.push_back(std::move(c));
    }
    return out;
  }();
  return all;
}

template <typename Check>
void forEachSample(Check&& check, int max_samples = 1000) {
  for (const TreeCase& c : trees()) {
    SCOPED_TRACE(c.name);
    for (int k = 0; k < static_cast<int>(c.samples.size()) && k < max_samples; ++k) {
      SCOPED_TRACE("sample " + std::to_string(k));
      check(c.model, c.samples[k]);
    }
  }
}

// The generator produces what the other tests rely on: valid models and every feature.
TEST(RandomTrees, AreValidAndCoverEveryFeature) {
  int aligned = 0, unaligned = 0, prismatic = 0, free_flyers = 0, body_frames = 0,
      frames_on_universe = 0, max_depth = 0, max_children = 0, offset_bodies = 0;
  for (const TreeCase& c : trees()) {
    SCOPED_TRACE(c.name);
    const Model& m = c.model;
    EXPECT_EQ(m.nq, m.nv + (m.hasFreeFlyer() ? 1 : 0));
    EXPECT_EQ(static_cast<int>(m.parentDof.size()), m.nv);
    EXPECT_EQ(m.lowerPositionLimit.size(), m.nq);
    free_flyers += m.hasFreeFlyer();
    std::vector<int> depth(m.njoints(), 0), children(m.njoints(), 0);
    for (int i = 1; i < m.njoints(); ++i) {
      const Joint& j = m.joints[i];
      ASSERT_GE(j.parent, 0);
      ASSERT_LT(j.parent, i);
      depth[i] = depth[j.parent] + 1;
      ++children[j.parent];
      max_depth = std::max(max_depth, depth[i]);
      if (j.type == JointType::Revolute) (j.alignedAxis >= 0 ? aligned : unaligned)++;
      if (j.type == JointType::Prismatic) ++prismatic;
      EXPECT_NEAR(j.axis.norm(), 1.0, 1e-15);
      // Physically valid bodies: positive mass, inertia about the CoM positive definite and
      // satisfying the triangle inequality.
      const Inertia& Y = m.inertias[i];
      EXPECT_GT(Y.m, 0.0);
      const Eigen::Vector3d principal =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(Y.inertiaAboutCom()).eigenvalues();
      EXPECT_GT(principal.minCoeff(), 0.0);
      EXPECT_GE(principal[0] + principal[1], principal[2] * (1 - 1e-12));
      if (Y.com().norm() > 0.1 + 1e-9) ++offset_bodies;  // only offset placements reach this
      if (j.nq == 1 && std::isfinite(m.lowerPositionLimit[j.idx_q])) {
        EXPECT_LE(m.lowerPositionLimit[j.idx_q], 0.0);
        EXPECT_GE(m.upperPositionLimit[j.idx_q], 0.0);
      }
    }
    for (int c2 : children) max_children = std::max(max_children, c2);
    for (const Frame& f : m.frames) {
      if (f.type == FrameType::Body) ++body_frames;
      if (f.type == FrameType::Operational && f.parentJoint == 0 && f.name != "universe")
        ++frames_on_universe;
    }
  }
  EXPECT_EQ(free_flyers, kTrees / 2);
  EXPECT_GT(aligned, 20);
  EXPECT_GT(unaligned, 20);
  EXPECT_GT(prismatic, 20);
  EXPECT_GT(body_frames, 20);
  EXPECT_GT(offset_bodies, 5);
  EXPECT_GT(frames_on_universe, 0);
  EXPECT_GE(max_depth, 12);    // long chains
  EXPECT_GE(max_children, 4);  // bushy stars
}

TEST(RandomTrees, AbaEqualsCrbaSolve) {
  forEachSample(checks::abaMatchesCrbaSolve);
}

TEST(RandomTrees, RneaEqualsMassMatrixTimesAccelerationPlusBias) {
  forEachSample(checks::rneaMatchesMassMatrixAndBias);
}

// Symmetric positive definite, and 1/2 v^T M v = 1/2 sum_i v_i^T Y_i v_i.
TEST(RandomTrees, MassMatrixIsSpdAndGivesKineticEnergy) {
  forEachSample(checks::massMatrixIsSpdAndGivesKineticEnergy);
}

TEST(RandomTrees, FrameJacobiansMatchFiniteDifferences) {
  forEachSample([](const Model& model, const checks::Sample& s) {
    checks::placementJacobiansMatchFiniteDifferences(model, s, true);
  });
}

TEST(RandomTrees, JointJacobiansMatchFiniteDifferences) {
  forEachSample([](const Model& model, const checks::Sample& s) {
    checks::placementJacobiansMatchFiniteDifferences(model, s, false);
  });
}

TEST(RandomTrees, FrameAccelerationsMatchTimeDerivatives) {
  forEachSample(checks::frameAccelerationsMatchTimeDerivatives, 1);
}

TEST(RandomTrees, ComJacobianMatchesFiniteDifferences) {
  forEachSample(checks::comJacobianMatchesFiniteDifferences);
}

TEST(RandomTrees, CentroidalMapTimesVelocityIsMomentum) {
  forEachSample(checks::centroidalMapMatchesMomentum);
}

}  // namespace test_random_trees
}  // namespace stride
