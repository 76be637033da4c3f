// KnotModel's kept contact solve (knot.hpp, KeptSolve): a calcDiff at the point of the last calc
// takes calc's solve instead of solving again, and must give bit for bit what a calcDiff from
// scratch gives, for every kind of residual (each reads its own part of the kinematics the kept
// solve restores), knots sharing one workspace (so another knot's calc runs in between), and
// repeated calls. Any change that makes the kept solve stale (x, u, dt, damping, the contact set)
// must send calcDiff back to a full solve.
//
// The same knot integrating by RK4 (KnotModel::setIntegrator): its Fx, Fu and cost derivatives
// against finite differences, impulses unchanged, the costs reading stage 1 (the Euler knot's
// solve at x), and no kept solve.

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>

#include "ocp/residual_cases.hpp"
#include "solver/ocp/knot.hpp"

namespace stride {
namespace test_knot {

using ocp_test::makeTerms;
using ocp_test::randomState;
using ocp_test::randomUniform;
using ocp_test::RobotSetup;
using ocp_test::robotSetups;
using ocp_test::Term;

constexpr int kKnots = 3;

struct Knots {
  std::vector<std::unique_ptr<KnotModel>> models;
  std::vector<Eigen::VectorXd> xs, us;
};

Knots makeKnots(const RobotSetup& s, std::mt19937& rng, Integrator integrator = Integrator::Euler) {
  Knots k;
  auto workspace = std::make_shared<SharedWorkspace>(s.model, 1);
  const int nu = actuatedDimension(s.model);
  for (int i = 0; i < kKnots; ++i) {
    k.xs.push_back(randomState(s.model, rng));
    k.us.push_back(randomUniform(rng, nu, 5.0));
    auto m = std::make_unique<KnotModel>(s.model, s.contacts, 0.01, workspace);
    m->setIntegrator(integrator);
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

// ---- RK4 knots ----

// max|a - b| / max(1, max|b|)
double relErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return 1e9;
  if (b.size() == 0) return 0.0;
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

// The knot's outputs at (x, u) by calc: x⁺ (for differences) and the cost.
struct Outputs {
  Eigen::VectorXd x_next;
  double cost;
};

Outputs outputsAt(const KnotModel& m, ActionData& d, const Eigen::VectorXd& x,
                  const Eigen::VectorXd& u) {
  m.calc(d, x, u);
  EXPECT_EQ(d.status, KnotStatus::Ok);
  return {d.x_next, d.cost};
}

// Central differences of x⁺ (in the tangent space at the knot's x⁺) and of the cost, with respect
// to dx (x ⊕ dx) and u, against calcDiff's Fx, Fu, Lx, Lu. The step and tolerance are those of
// the RK4 knot's own test (tests/contact/test_knot_rk4.cpp: with random states and ±5 N m the
// later stages see large accelerations, and the differences of v⁺ lose ~1e-7 to rounding at
// h = 1e-5).
void expectDerivativesMatchFiniteDifferences(const KnotModel& m, const Eigen::VectorXd& x,
                                             const Eigen::VectorXd& u, const char* what) {
  SCOPED_TRACE(what);
  constexpr double kStep = 1e-5, kTol = 2e-6;
  const StateSpace& space = m.state();
  const int ndx = space.ndx(), nu = static_cast<int>(u.size());
  auto d = m.createData();
  m.calcDiff(*d, x, u);
  ASSERT_EQ(d->status, KnotStatus::Ok);
  const Eigen::MatrixXd Fx = d->Fx, Fu = d->Fu;
  const Eigen::VectorXd Lx = d->Lx, Lu = d->Lu, x_next = d->x_next;
  auto fd = m.createData();
  Eigen::MatrixXd Nx(ndx, ndx), Nu(ndx, nu);
  Eigen::VectorXd NLx(ndx), NLu(nu);
  Eigen::VectorXd xp(x.size()), xm(x.size()), dp(ndx), dm(ndx);
  auto column = [&](const Outputs& p, const Outputs& n, Eigen::Ref<Eigen::VectorXd> col,
                    double& grad) {
    space.difference(x_next, p.x_next, dp);
    space.difference(x_next, n.x_next, dm);
    col = (dp - dm) / (2 * kStep);
    grad = (p.cost - n.cost) / (2 * kStep);
  };
  for (int k = 0; k < ndx; ++k) {
    const Eigen::VectorXd e = kStep * Eigen::VectorXd::Unit(ndx, k);
    space.integrate(x, e, xp);
    space.integrate(x, -e, xm);
    column(outputsAt(m, *fd, xp, u), outputsAt(m, *fd, xm, u), Nx.col(k), NLx[k]);
  }
  for (int k = 0; k < nu; ++k) {
    const Eigen::VectorXd e = kStep * Eigen::VectorXd::Unit(nu, k);
    column(outputsAt(m, *fd, x, u + e), outputsAt(m, *fd, x, u - e), Nu.col(k), NLu[k]);
  }
  EXPECT_LT(relErr(Fx, Nx), kTol) << "Fx";
  EXPECT_LT(relErr(Fu, Nu), kTol) << "Fu";
  EXPECT_LT(relErr(Lx.transpose(), NLx.transpose()), kTol) << "Lx";
  EXPECT_LT(relErr(Lu.transpose(), NLu.transpose()), kTol) << "Lu";
  std::printf("  %-34s Fx %.1e  Fu %.1e  Lx %.1e  Lu %.1e\n", what, relErr(Fx, Nx), relErr(Fu, Nu),
              relErr(Lx.transpose(), NLx.transpose()), relErr(Lu.transpose(), NLu.transpose()));
}

// A point-foot quadruped (solo12, four 3D contacts) and a flat-foot humanoid (talos_reduced, two
// 6D soles), with one residual of every kind, the force, cone and centre-of-pressure terms
// included: Fx, Fu through the four stages and the cost's gradient, whose force terms read
// stage 1's λ and its Jacobians.
TEST(KnotModelRk4, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(21);
  for (const RobotSetup& s : robotSetups()) {
    SCOPED_TRACE(s.name);
    Knots k = makeKnots(s, rng, Integrator::Rk4);
    KnotModel& m = *k.models[0];
    ASSERT_EQ(m.integrator(), Integrator::Rk4);
    expectDerivativesMatchFiniteDifferences(m, k.xs[0], k.us[0], (s.name + " contact").c_str());
    // A contact switched off: fewer rows of λ for the force terms to find theirs in.
    m.contacts().setActive(1, false);
    expectDerivativesMatchFiniteDifferences(m, k.xs[0], k.us[0],
                                            (s.name + " one contact off").c_str());
    m.contacts().setActive(1, true);
  }
}

// An impulse knot of an RK4 problem is the impulse of an Euler one: instantaneous, bit for bit
// the same, and its derivatives match finite differences.
TEST(KnotModelRk4, ImpulseKnotIsUnchanged) {
  std::mt19937 rng(22);
  for (const RobotSetup& s : robotSetups()) {
    SCOPED_TRACE(s.name);
    std::mt19937 rng_euler = rng;
    Knots rk4 = makeKnots(s, rng, Integrator::Rk4);
    Knots euler = makeKnots(s, rng_euler, Integrator::Euler);
    rk4.models[0]->setMode(KnotMode::Impulse);
    euler.models[0]->setMode(KnotMode::Impulse);
    auto dr = rk4.models[0]->createData(), de = euler.models[0]->createData();
    rk4.models[0]->calcDiff(*dr, rk4.xs[0], rk4.us[0]);
    euler.models[0]->calcDiff(*de, euler.xs[0], euler.us[0]);
    expectSameDerivatives(knotData(dr), knotData(de), "impulse, rk4 vs euler");
    EXPECT_FALSE(dr->euler.valid);
    expectDerivativesMatchFiniteDifferences(*rk4.models[0], rk4.xs[0], rk4.us[0],
                                            (s.name + " impulse").c_str());
  }
}

// λ of an RK4 knot is stage 1's, the contact dynamics at x: the Euler knot's. The costs read it,
// its Jacobians and the kinematics at x, so everything but x⁺, Fx, Fu is the Euler knot's.
// RK4 never takes a kept solve and never claims the Euler structure of Fx.
TEST(KnotModelRk4, CostsReadStageOneTheEulerKnotsSolve) {
  std::mt19937 rng(23);
  for (const RobotSetup& s : robotSetups()) {
    SCOPED_TRACE(s.name);
    std::mt19937 rng_euler = rng;
    Knots rk4 = makeKnots(s, rng, Integrator::Rk4);
    Knots euler = makeKnots(s, rng_euler, Integrator::Euler);
    for (int i = 0; i < kKnots; ++i) {
      auto dr = rk4.models[i]->createData(), de = euler.models[i]->createData();
      rk4.models[i]->calc(*dr, rk4.xs[i], rk4.us[i]);
      rk4.models[i]->calcDiff(*dr, rk4.xs[i], rk4.us[i]);
      euler.models[i]->calcDiff(*de, euler.xs[i], euler.us[i]);
      const KnotActionData &r = knotData(dr), &e = knotData(de);
      ASSERT_EQ(r.status, KnotStatus::Ok);
      ASSERT_EQ(e.status, KnotStatus::Ok);
      EXPECT_FALSE(r.solve_reused);
      EXPECT_FALSE(r.euler.valid);
      EXPECT_TRUE(e.euler.valid);
      EXPECT_EQ(r.nc(), e.nc());
      EXPECT_TRUE(r.forces() == e.forces()) << "knot " << i;
      EXPECT_EQ(r.cost, e.cost) << "knot " << i;
      EXPECT_TRUE(r.Lx == e.Lx && r.Lu == e.Lu && r.Lxx == e.Lxx && r.Lxu == e.Lxu &&
                  r.Luu == e.Luu)
          << "knot " << i;
      // The integrators differ: x⁺ is not Euler's (O(dt²) apart).
      EXPECT_FALSE(r.x_next == e.x_next);
    }
  }
}

// Knots of both integrators share one workspace (each gets a slot of its kind), and calc /
// calcDiff on shared scratch give what a knot with its own workspace gives.
TEST(KnotModelRk4, SharedWorkspaceServesBothIntegrators) {
  std::mt19937 rng(24);
  const RobotSetup s = std::move(robotSetups().front());
  const int nu = actuatedDimension(s.model);
  auto workspace = std::make_shared<SharedWorkspace>(s.model, 1);
  std::vector<std::unique_ptr<KnotModel>> shared, own;
  std::vector<Eigen::VectorXd> xs, us;
  std::mt19937 terms_rng(25);
  for (int i = 0; i < 4; ++i) {
    xs.push_back(randomState(s.model, rng));
    us.push_back(randomUniform(rng, nu, 5.0));
    const Integrator integrator = i % 2 ? Integrator::Rk4 : Integrator::Euler;
    for (auto* list : {&shared, &own}) {
      auto m = std::make_unique<KnotModel>(s.model, s.contacts, 0.01,
                                           list == &shared ? workspace : nullptr);
      m->setIntegrator(integrator);
      std::mt19937 r = terms_rng;  // the same terms for both
      for (auto& t : makeTerms(s, nu, xs.back(), r))
        m->costs().add(t.name, std::move(t.residual), std::move(t.activation), 1.0);
      list->push_back(std::move(m));
    }
    terms_rng.discard(1000);
  }
  std::vector<std::unique_ptr<ActionData>> ds, dow;
  for (int i = 0; i < 4; ++i) {
    ds.push_back(shared[i]->createData());
    dow.push_back(own[i]->createData());
  }
  for (int i = 0; i < 4; ++i) shared[i]->calc(*ds[i], xs[i], us[i]);
  for (int i = 0; i < 4; ++i) {
    shared[i]->calcDiff(*ds[i], xs[i], us[i]);
    own[i]->calcDiff(*dow[i], xs[i], us[i]);
    expectSameDerivatives(knotData(ds[i]), knotData(dow[i]), "shared vs own workspace");
    EXPECT_EQ(knotData(ds[i]).solve_reused, i % 2 == 0) << "knot " << i;
  }
}

// The integrator is set up before createData: data made for the other one is refused, not
// silently integrated otherwise.
TEST(KnotModelRk4, DataOfTheOtherIntegratorIsRefused) {
  std::mt19937 rng(26);
  const RobotSetup s = std::move(robotSetups().front());
  Knots k = makeKnots(s, rng);
  KnotModel& m = *k.models[0];
  auto d = m.createData();
  m.setIntegrator(Integrator::Rk4);
  EXPECT_THROW(m.calc(*d, k.xs[0], k.us[0]), std::logic_error);
  auto d4 = m.createData();
  m.calc(*d4, k.xs[0], k.us[0]);
  EXPECT_EQ(d4->status, KnotStatus::Ok);
  Integrator parsed = Integrator::Euler;
  EXPECT_TRUE(parseIntegrator("rk4", parsed));
  EXPECT_EQ(parsed, Integrator::Rk4);
  EXPECT_FALSE(parseIntegrator("RK4", parsed));
  EXPECT_EQ(parsed, Integrator::Rk4);
  EXPECT_STREQ(toString(Integrator::Euler), "euler");
}

}  // namespace test_knot
}  // namespace stride
