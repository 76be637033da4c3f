// KnotModel's kept contact solve (knot.hpp, KeptSolve): a calcDiff at the point of the last calc
// takes calc's solve instead of solving again, and must give bit for bit what a calcDiff from
// scratch gives, for every kind of residual (each reads its own part of the kinematics the kept
// solve restores), knots sharing one workspace (so another knot's calc runs in between), and
// repeated calls. Any change that makes the kept solve stale (x, u, dt, damping, the contact set)
// must send calcDiff back to a full solve.

#include <gtest/gtest.h>

#include <random>

#include "ocp/residual_cases.hpp"
#include "solver/ocp/knot.hpp"

namespace stride {
namespace {

using ocp_test::makeTerms;
using ocp_test::randomState;
using ocp_test::randomUniform;
using ocp_test::RobotSetup;
using ocp_test::robotSetups;

constexpr int kKnots = 3;

struct Knots {
  std::vector<std::unique_ptr<KnotModel>> models;
  std::vector<Eigen::VectorXd> xs, us;
};

Knots makeKnots(const RobotSetup& s, std::mt19937& rng) {
  Knots k;
  auto workspace = std::make_shared<SharedWorkspace>(s.model, 1);
  const int nu = actuatedDimension(s.model);
  for (int i = 0; i < kKnots; ++i) {
    k.xs.push_back(randomState(s.model, rng));
    k.us.push_back(randomUniform(rng, nu, 5.0));
    auto m = std::make_unique<KnotModel>(s.model, s.contacts, 0.01, workspace);
    for (auto& t : makeTerms(s, nu, k.xs.back(), rng))
      m->costs().add(t.name, std::move(t.residual), std::move(t.activation), 1.0);
    k.models.push_back(std::move(m));
  }
  return k;
}

// Everything calcDiff outputs, compared exactly.
void expectSameDerivatives(const KnotActionData& a, const KnotActionData& b, const char* what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(a.status, KnotStatus::Ok);
  ASSERT_EQ(b.status, KnotStatus::Ok);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_TRUE(a.x_next == b.x_next);
  EXPECT_TRUE(a.forces() == b.forces());
  EXPECT_TRUE(a.Fx == b.Fx);
  EXPECT_TRUE(a.Fu == b.Fu);
  EXPECT_TRUE(a.Lx == b.Lx);
  EXPECT_TRUE(a.Lu == b.Lu);
  EXPECT_TRUE(a.Lxx == b.Lxx);
  EXPECT_TRUE(a.Lxu == b.Lxu);
  EXPECT_TRUE(a.Luu == b.Luu);
}

KnotActionData& knotData(std::unique_ptr<ActionData>& d) {
  return static_cast<KnotActionData&>(*d);
}

TEST(KnotModel, CalcDiffAfterCalcTakesTheKeptSolveBitForBit) {
  std::mt19937 rng(11);
  for (const RobotSetup& s : robotSetups()) {
    SCOPED_TRACE(s.name);
    Knots k = makeKnots(s, rng);
    std::vector<std::unique_ptr<ActionData>> kept, fresh;
    for (const auto& m : k.models) {
      kept.push_back(m->createData());
      fresh.push_back(m->createData());
    }
    // calc on every knot first: the knots share one workspace, so each calcDiff below runs after
    // the other knots' solves have gone through it.
    for (int i = 0; i < kKnots; ++i) k.models[i]->calc(*kept[i], k.xs[i], k.us[i]);
    for (int i = 0; i < kKnots; ++i) {
      k.models[i]->calcDiff(*kept[i], k.xs[i], k.us[i]);
      EXPECT_TRUE(knotData(kept[i]).solve_reused) << "knot " << i;
    }
    for (int i = 0; i < kKnots; ++i) {
      k.models[i]->calcDiff(*fresh[i], k.xs[i], k.us[i]);
      EXPECT_FALSE(knotData(fresh[i]).solve_reused) << "knot " << i;
      expectSameDerivatives(knotData(kept[i]), knotData(fresh[i]), "after calc");
    }
    // Again: calcDiff hands the solve back to the knot, so it still serves.
    for (int i = 0; i < kKnots; ++i) {
      k.models[i]->calcDiff(*kept[i], k.xs[i], k.us[i]);
      EXPECT_TRUE(knotData(kept[i]).solve_reused) << "knot " << i;
      expectSameDerivatives(knotData(kept[i]), knotData(fresh[i]), "second calcDiff");
    }
  }
}

TEST(KnotModel, AStaleKeptSolveIsNotTaken) {
  std::mt19937 rng(12);
  const RobotSetup s = std::move(robotSetups().front());  // solo12, four feet
  Knots k = makeKnots(s, rng);
  KnotModel& m = *k.models[0];
  auto kept = m.createData();
  auto fresh = m.createData();
  const Eigen::VectorXd& u = k.us[0];
  // Each change after calc: calcDiff must solve again, and agree with a calcDiff from scratch.
  const std::vector<std::pair<const char*, std::function<void(Eigen::VectorXd&)>>> changes = {
      {"x", [](Eigen::VectorXd& x) { x[x.size() - 1] += 1e-9; }},
      {"dt", [&m](Eigen::VectorXd&) { m.setDt(0.005); }},
      {"damping", [&m](Eigen::VectorXd&) { m.damping = 1e-6; }},
      {"contact switched", [&m](Eigen::VectorXd&) { m.contacts().setActive(1, false); }},
      {"contact reference",
       [&m](Eigen::VectorXd&) {
         m.contacts().setReference(0, SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1)));
       }},
  };
  for (const auto& [what, change] : changes) {
    SCOPED_TRACE(what);
    Eigen::VectorXd x = k.xs[0];
    m.calc(*kept, x, u);
    change(x);
    m.calcDiff(*kept, x, u);
    EXPECT_FALSE(knotData(kept).solve_reused);
    m.calcDiff(*fresh, x, u);
    expectSameDerivatives(knotData(kept), knotData(fresh), what);
  }
  // Another knot's data, or the impulse mode, never takes it either.
  m.calc(*kept, k.xs[0], u);
  k.models[1]->calcDiff(*kept, k.xs[0], u);
  EXPECT_FALSE(knotData(kept).solve_reused);
  m.calc(*kept, k.xs[0], u);
  m.setMode(KnotMode::Impulse);
  m.calcDiff(*kept, k.xs[0], u);
  EXPECT_FALSE(knotData(kept).solve_reused);
}

}  // namespace
}  // namespace stride
