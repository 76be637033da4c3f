// Residual models of solver/ocp: every Jacobian against central finite differences on the state
// manifold (forces recomputed by the knot dynamics at each perturbed point, so λ moves with x and
// u), the sparse Gauss-Newton overrides against the dense default, independent routes for the
// whole-body quantities, the physics of the force residuals, the cost gradient against finite
// differences of the cost, and bad construction arguments.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "ocp/residual_cases.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/ocp/cost.hpp"

namespace stride {
namespace test_residuals {

using ocp_test::Knot;
using ocp_test::makeTerms;
using ocp_test::randomState;
using ocp_test::randomUniform;
using ocp_test::RobotSetup;
using ocp_test::robotSetups;
using ocp_test::Term;

// Central differences with h = 1e-6: truncation ~h² |r'''| ≈ 1e-12 and rounding
// ~1e-16 |r| / h ≈ 1e-10 |r| (forces of ~1e3 N: 1e-7), so 1e-6 relative to max(1, max|R|) leaves
// two orders of margin while any wrong term (errors of order |R|) fails by far.
constexpr double kStep = 1e-6;
constexpr double kTol = 1e-6;

// max|a - b| / max(1, max|b|)
double relErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return 1e9;
  if (b.size() == 0) return 0.0;
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

// Columns of Rx that dependence() says may be nonzero.
int stateColumns(const Residual& r) {
  switch (r.dependence()) {
    case Dependence::Configuration:
      return r.nv();
    case Dependence::Control:
      return 0;
    default:
      return 2 * r.nv();
  }
}
bool hasControl(const Residual& r) {
  return r.dependence() == Dependence::Control || r.dependence() == Dependence::StateControl;
}

// Rx, Ru by central differences: x ⊕ ±h e_j on the manifold, u ± h e_j, with the knot (and so the
// forces) recomputed at every point.
void finiteDifferences(const Residual& res, Knot& knot, const StateSpace& space,
                       const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::MatrixXd& Rx,
                       Eigen::MatrixXd& Ru) {
  auto d = res.createData();
  const int ndx = space.ndx(), nu = static_cast<int>(u.size());
  Rx.resize(res.dim(), ndx);
  Ru.resize(res.dim(), nu);
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(ndx), xp(x.size()), xm(x.size()), rp;
  for (int j = 0; j < ndx; ++j) {
    dx[j] = kStep;
    space.integrate(x, dx, xp);
    dx[j] = -kStep;
    space.integrate(x, dx, xm);
    dx[j] = 0.0;
    res.calc(*d, knot.at(xp, u), xp, u);
    rp = d->r;
    res.calc(*d, knot.at(xm, u), xm, u);
    Rx.col(j) = (rp - d->r) / (2 * kStep);
  }
  for (int j = 0; j < nu; ++j) {
    Eigen::VectorXd up = u, um = u;
    up[j] += kStep;
    um[j] -= kStep;
    res.calc(*d, knot.at(x, up), x, up);
    rp = d->r;
    res.calc(*d, knot.at(x, um), x, um);
    Ru.col(j) = (rp - d->r) / (2 * kStep);
  }
}

void expectJacobiansMatch(const Term& term, Knot& knot, const StateSpace& space,
                          const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                          const std::string& where) {
  const Residual& res = *term.residual;
  auto d = res.createData();
  const KnotContext ctx = knot.at(x, u);
  ASSERT_EQ(knot.status, ContactStatus::Ok) << where;
  res.calc(*d, ctx, x, u);
  res.calcDiff(*d, ctx, x, u);
  Eigen::MatrixXd Rx_fd, Ru_fd;
  finiteDifferences(res, knot, space, x, u, Rx_fd, Ru_fd);
  const std::string what = where + " " + term.name;
  const int nx = stateColumns(res);
  EXPECT_LT(relErr(d->Rx.leftCols(nx), Rx_fd.leftCols(nx)), kTol) << what << ": Rx";
  // The columns dependence() excludes are never read: the residual must really not depend on them.
  const int ndx = space.ndx();
  EXPECT_LT(relErr(Eigen::MatrixXd::Zero(res.dim(), ndx - nx), Rx_fd.rightCols(ndx - nx)), kTol)
      << what << ": depends on state columns its dependence() excludes";
  if (hasControl(res))
    EXPECT_LT(relErr(d->Ru, Ru_fd), kTol) << what << ": Ru";
  else
    EXPECT_LT(relErr(Eigen::MatrixXd::Zero(res.dim(), Ru_fd.cols()), Ru_fd), kTol)
        << what << ": depends on u but its dependence() says not";
}

TEST(Residuals, JacobiansMatchFiniteDifferences) {
  std::mt19937 rng(11);
  for (RobotSetup& s : robotSetups()) {
    const StateSpace space(s.model);
    for (int sample = 0; sample < 2; ++sample) {
      const Eigen::VectorXd x = randomState(s.model, rng);
      Knot knot(s.model, s.contacts);
      const Eigen::VectorXd u = randomUniform(rng, knot.kd.nu, 5.0);
      const std::vector<Term> terms = makeTerms(s, knot.kd.nu, x, rng);
      for (const Term& t : terms)
        expectJacobiansMatch(t, knot, space, x, u, s.name + " sample " + std::to_string(sample));
    }
  }
}

// With the first contact off the force residuals on it vanish with their Jacobians, and those on
// the others read the right (shifted) rows.
TEST(Residuals, ForceJacobiansWithAContactOff) {
  std::mt19937 rng(12);
  for (RobotSetup& s : robotSetups()) {
    const StateSpace space(s.model);
    s.contacts.setActive(0, false);
    const Eigen::VectorXd x = randomState(s.model, rng);
    Knot knot(s.model, s.contacts);
    const Eigen::VectorXd u = randomUniform(rng, knot.kd.nu, 5.0);
    const std::vector<Term> terms = makeTerms(s, knot.kd.nu, x, rng);
    for (const Term& t : terms) {
      if (t.residual->dependence() != Dependence::StateControl) continue;
      expectJacobiansMatch(t, knot, space, x, u, s.name + " first contact off");
      auto d = t.residual->createData();
      const KnotContext ctx = knot.at(x, u);
      t.residual->calc(*d, ctx, x, u);
      t.residual->calcDiff(*d, ctx, x, u);
      const bool off = t.name.find(s.contacts[0].name) != std::string::npos;
      if (off) {
        EXPECT_TRUE(d->r.isZero(0.0)) << s.name << " " << t.name;
        EXPECT_TRUE(d->Rx.isZero(0.0)) << s.name << " " << t.name;
        EXPECT_TRUE(d->Ru.isZero(0.0)) << s.name << " " << t.name;
      } else {
        EXPECT_GT(d->Rx.norm(), 0.0) << s.name << " " << t.name;
      }
    }
  }
}

// Random g, h ≥ 0 and random starting derivatives: each override adds exactly what the dense
// default of the base class adds.
TEST(Residuals, GaussNewtonOverridesMatchDenseDefault) {
  std::mt19937 rng(13);
  for (RobotSetup& s : robotSetups()) {
    const Eigen::VectorXd x = randomState(s.model, rng);
    Knot knot(s.model, s.contacts);
    const int nu = knot.kd.nu, ndx = 2 * s.model.nv;
    const Eigen::VectorXd u = randomUniform(rng, nu, 5.0);
    const KnotContext ctx = knot.at(x, u);
    const std::vector<Term> terms = makeTerms(s, nu, x, rng);
    int overrides = 0;
    for (const Term& t : terms) {
      const Residual& res = *t.residual;
      auto d = res.createData();
      res.calc(*d, ctx, x, u);
      res.calcDiff(*d, ctx, x, u);
      const int m = res.dim();
      const Eigen::VectorXd g = randomUniform(rng, m, 2.0);
      const Eigen::VectorXd h = randomUniform(rng, m, 2.0).cwiseAbs();
      struct Out {
        Eigen::VectorXd Lx, Lu;
        Eigen::MatrixXd Lxx, Lxu, Luu, HRx, HRu;
      } a, b;
      a.Lx = randomUniform(rng, ndx, 1.0);
      a.Lu = randomUniform(rng, nu, 1.0);
      a.Lxx = Eigen::MatrixXd::Random(ndx, ndx);
      a.Lxu = Eigen::MatrixXd::Random(ndx, nu);
      a.Luu = Eigen::MatrixXd::Random(nu, nu);
      a.HRx = Eigen::MatrixXd::Zero(m, ndx);
      a.HRu = Eigen::MatrixXd::Zero(m, nu);
      b = a;
      CostDerivatives oa{a.Lx, a.Lu, a.Lxx, a.Lxu, a.Luu, a.HRx, a.HRu};
      CostDerivatives ob{b.Lx, b.Lu, b.Lxx, b.Lxu, b.Luu, b.HRx, b.HRu};
      res.addGaussNewton(*d, g, h, oa);
      res.Residual::addGaussNewton(*d, g, h, ob);
      const std::string what = s.name + " " + t.name;
      EXPECT_LT(relErr(a.Lx, b.Lx), 1e-12) << what;
      EXPECT_LT(relErr(a.Lu, b.Lu), 1e-12) << what;
      EXPECT_LT(relErr(a.Lxx, b.Lxx), 1e-12) << what;
      EXPECT_LT(relErr(a.Lxu, b.Lxu), 1e-12) << what;
      EXPECT_LT(relErr(a.Luu, b.Luu), 1e-12) << what;
      if (t.name == "state" || t.name == "control" || t.name == "limits" || t.name == "translation")
        ++overrides;
    }
    EXPECT_EQ(overrides, 4);
  }
}

// The default addGaussNewton itself against the products written out densely (Rᵀ g, Rᵀ diag(h) R
// over all columns), for every residual and for curvature patterns that take each of its routes:
// no row curved (gradient only), one or two rows curved (rank-1 updates), all rows curved (dense
// products); g is zero on some rows, as a bounds activation's inside its bounds.
TEST(Residuals, GaussNewtonDefaultMatchesDenseProducts) {
  std::mt19937 rng(17);
  for (RobotSetup& s : robotSetups()) {
    const Eigen::VectorXd x = randomState(s.model, rng);
    Knot knot(s.model, s.contacts);
    const int nu = knot.kd.nu, ndx = 2 * s.model.nv;
    const Eigen::VectorXd u = randomUniform(rng, nu, 5.0);
    const KnotContext ctx = knot.at(x, u);
    const std::vector<Term> terms = makeTerms(s, nu, x, rng);
    for (const Term& t : terms) {
      const Residual& res = *t.residual;
      auto d = res.createData();
      res.calc(*d, ctx, x, u);
      res.calcDiff(*d, ctx, x, u);
      const int m = res.dim();
      // Only the columns dependence() names are read: the reference uses those alone.
      const int nx = stateColumns(res);
      Eigen::MatrixXd Rx = Eigen::MatrixXd::Zero(m, ndx), Ru = Eigen::MatrixXd::Zero(m, nu);
      Rx.leftCols(nx) = d->Rx.leftCols(nx);
      if (hasControl(res)) Ru = d->Ru;
      for (int curved : {0, 1, 2, m}) {
        if (curved > m) continue;
        Eigen::VectorXd g = randomUniform(rng, m, 2.0), h = Eigen::VectorXd::Zero(m);
        for (int i = 0; i < curved; ++i) h[(3 * i + 1) % m] = 0.5 + std::abs(g[i]);
        if (m > 1) g[m / 2] = 0.0;
        Eigen::VectorXd Lx = randomUniform(rng, ndx, 1.0), Lu = randomUniform(rng, nu, 1.0);
        Eigen::MatrixXd Lxx = Eigen::MatrixXd::Random(ndx, ndx);
        Eigen::MatrixXd Lxu = Eigen::MatrixXd::Random(ndx, nu);
        Eigen::MatrixXd Luu = Eigen::MatrixXd::Random(nu, nu);
        const Eigen::VectorXd Lx_ref = Lx + Rx.transpose() * g, Lu_ref = Lu + Ru.transpose() * g;
        const Eigen::MatrixXd Lxx_ref = Lxx + Rx.transpose() * h.asDiagonal() * Rx;
        const Eigen::MatrixXd Lxu_ref = Lxu + Rx.transpose() * h.asDiagonal() * Ru;
        const Eigen::MatrixXd Luu_ref = Luu + Ru.transpose() * h.asDiagonal() * Ru;
        Eigen::MatrixXd HRx = Eigen::MatrixXd::Zero(m, ndx), HRu = Eigen::MatrixXd::Zero(m, nu);
        CostDerivatives out{Lx, Lu, Lxx, Lxu, Luu, HRx, HRu};
        res.Residual::addGaussNewton(*d, g, h, out);
        const std::string what = s.name + " " + t.name + " curved rows " + std::to_string(curved);
        EXPECT_LT(relErr(Lx, Lx_ref), 1e-12) << what;
        EXPECT_LT(relErr(Lu, Lu_ref), 1e-12) << what;
        EXPECT_LT(relErr(Lxx, Lxx_ref), 1e-12) << what;
        EXPECT_LT(relErr(Lxu, Lxu_ref), 1e-12) << what;
        EXPECT_LT(relErr(Luu, Luu_ref), 1e-12) << what;
      }
    }
  }
}

// CoM, its Jacobian, the centroidal momentum and A_g against the multibody library's own routes.
TEST(Residuals, WholeBodyResidualsAgreeWithMultibody) {
  std::mt19937 rng(14);
  for (RobotSetup& s : robotSetups()) {
    const Model& m = s.model;
    const Eigen::VectorXd x = randomState(m, rng);
    Knot knot(m, s.contacts);
    const int nu = knot.kd.nu;
    const Eigen::VectorXd u = Eigen::VectorXd::Zero(nu);
    const KnotContext ctx = knot.at(x, u);
    ComPositionResidual com(m, nu);
    CentroidalMomentumResidual hg(m, nu);
    auto dc = com.createData(), dh = hg.createData();
    com.calc(*dc, ctx, x, u);
    com.calcDiff(*dc, ctx, x, u);
    hg.calc(*dh, ctx, x, u);
    hg.calcDiff(*dh, ctx, x, u);
    Data ref(m);
    const Eigen::VectorXd q = x.head(m.nq), v = x.tail(m.nv);
    computeCentroidalMomentum(m, ref, q, v);
    EXPECT_LT(relErr(dh->r, ref.hg), 1e-12) << s.name;
    jacobianCenterOfMass(m, ref, q);
    EXPECT_LT(relErr(dc->r, ref.com), 1e-12) << s.name;
    EXPECT_LT(relErr(dc->Rx.leftCols(m.nv), ref.Jcom), 1e-12) << s.name;
    computeCentroidalMap(m, ref, q);
    EXPECT_LT(relErr(dh->Rx.rightCols(m.nv), ref.Ag), 1e-12) << s.name;
  }
}

// The force residual reads the contact's own rows of λ, Gx, Gu; forceOffset stacks the active
// contacts in set order.
TEST(Residuals, ContactForceMatchesLambda) {
  std::mt19937 rng(15);
  for (RobotSetup& s : robotSetups()) {
    const Model& m = s.model;
    const Eigen::VectorXd x = randomState(m, rng);
    Knot knot(m, s.contacts);
    const int nu = knot.kd.nu;
    const Eigen::VectorXd u = randomUniform(rng, nu, 5.0);
    const KnotContext ctx = knot.at(x, u);
    int offset = 0;
    for (int c = 0; c < s.contacts.size(); ++c) {
      const int dim = s.contacts[c].dim;
      EXPECT_EQ(forceOffset(s.contacts, c), offset);
      const Eigen::VectorXd ref = randomUniform(rng, dim, 10.0);
      ContactForceResidual f(m, nu, s.contacts, s.contacts[c].name, ref);
      auto d = f.createData();
      f.calc(*d, ctx, x, u);
      f.calcDiff(*d, ctx, x, u);
      EXPECT_TRUE(d->r.isApprox(knot.kd.contact.lambda.segment(offset, dim) - ref, 1e-14));
      EXPECT_TRUE(d->Rx.isApprox(knot.kd.Gx.middleRows(offset, dim), 1e-14));
      EXPECT_TRUE(d->Ru.isApprox(knot.kd.Gu.middleRows(offset, dim), 1e-14));
      offset += dim;
    }
    EXPECT_EQ(forceOffset(s.contacts, -1), -1);
    EXPECT_EQ(forceOffset(s.contacts, s.contacts.size()), -1);
    s.contacts.setActive(0, false);
    EXPECT_EQ(forceOffset(s.contacts, 0), -1);
    EXPECT_EQ(forceOffset(s.contacts, 1), 0);
    // A knot without contacts (terminal): zero.
    ContactForceResidual f(m, nu, s.contacts, s.contacts[1].name);
    auto d = f.createData();
    d->r.setConstant(1.0);
    const KnotContext bare{m, knot.data};
    f.calc(*d, bare, x, u);
    EXPECT_TRUE(d->r.isZero(0.0));
  }
}

// The cone's cost is zero for forces inside the inner pyramid (with any surface orientation) and
// positive outside it: too much tangential force, a pulling or too weak normal force.
TEST(Residuals, FrictionConeZeroInsidePositiveOutside) {
  RobotSetup s = std::move(robotSetups()[0]);
  const Model& m = s.model;
  const int nu = m.nv - 6;
  const double mu = 0.8, fmin = 2.0;
  const Eigen::Matrix3d Rs = exp3(Eigen::Vector3d(0.3, -0.2, 0.5));
  // Contact 1 of solo12 (LOCAL forces) sits at rows 3..5 of λ.
  FrictionConeResidual cone(m, nu, s.contacts, "FR_FOOT", mu, Rs, fmin);
  const Activation act = FrictionConeResidual::activation(1.0);
  auto d = cone.createData();
  Data data(m);
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(s.contacts.nc());
  const Eigen::MatrixXd Gx = Eigen::MatrixXd::Zero(s.contacts.nc(), 2 * m.nv);
  const Eigen::MatrixXd Gu = Eigen::MatrixXd::Zero(s.contacts.nc(), nu);
  const KnotContext ctx{m, data, &s.contacts, &lambda, &Gx, &Gu};
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(m.nq + m.nv), u = Eigen::VectorXd::Zero(nu);
  auto cost = [&](const Eigen::Vector3d& f_surface) {
    lambda.segment<3>(3) = Rs * f_surface;  // into the contact's force frame
    cone.calc(*d, ctx, x, u);
    return act.value(d->r);
  };
  const double mp = mu / std::sqrt(2.0);
  std::mt19937 rng(16);
  for (int k = 0; k < 100; ++k) {
    const double fz = fmin + 100.0 * std::uniform_real_distribution<double>(0, 1)(rng);
    const Eigen::Vector3d f(0.99 * mp * fz * randomUniform(rng, 1, 1.0)[0],
                            0.99 * mp * fz * randomUniform(rng, 1, 1.0)[0], fz);
    EXPECT_EQ(cost(f), 0.0) << f.transpose();
  }
  EXPECT_GT(cost(Eigen::Vector3d(1.01 * mp * 50, 0, 50)), 0.0);
  EXPECT_GT(cost(Eigen::Vector3d(0, -1.01 * mp * 50, 50)), 0.0);
  EXPECT_GT(cost(Eigen::Vector3d(0, 0, -10)), 0.0);
  EXPECT_GT(cost(Eigen::Vector3d(0, 0, 0.5 * fmin)), 0.0);
  // Inside the circular cone but outside the inscribed pyramid: rejected (the approximation is
  // conservative, never the other way round).
  EXPECT_GT(cost(Eigen::Vector3d(0.9 * mu * 50, 0, 50)), 0.0);
  // Rows in the force frame are the surface rows rotated: r = A f + [0; f_min].
  lambda.segment<3>(3) = Eigen::Vector3d(1, 2, 30);
  cone.calc(*d, ctx, x, u);
  Eigen::VectorXd expected = cone.rows() * Eigen::Vector3d(1, 2, 30);
  expected[4] += fmin;
  EXPECT_TRUE(d->r.isApprox(expected, 1e-14));
}

// The centre of pressure of a sole: zero cost while p = (−τ_y, τ_x) / f_z lies in the rectangle,
// positive outside it; in a rotated surface frame, the same after rotating the wrench.
TEST(Residuals, CenterOfPressureZeroInsidePositiveOutside) {
  RobotSetup s = std::move(robotSetups()[1]);  // talos_reduced: two 6D soles
  const Model& m = s.model;
  const int nu = m.nv - 6;
  const Eigen::Vector2d half(0.1, 0.05);
  const Eigen::Matrix3d Rs = exp3(Eigen::Vector3d(0.1, -0.2, 0.7));
  // The right sole (LOCAL forces) sits at rows 6..11 of λ.
  CenterOfPressureResidual cop(m, nu, s.contacts, "right_sole_link", half, Rs);
  const Activation act = CenterOfPressureResidual::activation(1.0);
  auto d = cop.createData();
  Data data(m);
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(s.contacts.nc());
  const Eigen::MatrixXd Gx = Eigen::MatrixXd::Zero(s.contacts.nc(), 2 * m.nv);
  const Eigen::MatrixXd Gu = Eigen::MatrixXd::Zero(s.contacts.nc(), nu);
  const KnotContext ctx{m, data, &s.contacts, &lambda, &Gx, &Gu};
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(m.nq + m.nv), u = Eigen::VectorXd::Zero(nu);
  // The wrench of a normal force fz at the point p of the sole, plus a yaw moment (free).
  auto cost = [&](double fz, const Eigen::Vector2d& p) {
    const Eigen::Vector3d f(0.0, 0.0, fz), at(p.x(), p.y(), 0.0);
    const Eigen::Vector3d tau = at.cross(f) + Eigen::Vector3d(0.0, 0.0, 3.0);
    lambda.segment<3>(6) = Rs * f;
    lambda.segment<3>(9) = Rs * tau;
    cop.calc(*d, ctx, x, u);
    return act.value(d->r);
  };
  std::mt19937 rng(18);
  for (int k = 0; k < 100; ++k) {
    const double fz = 1.0 + 300.0 * std::uniform_real_distribution<double>(0, 1)(rng);
    const Eigen::Vector2d p = 0.99 * half.cwiseProduct(randomUniform(rng, 2, 1.0));
    EXPECT_EQ(cost(fz, p), 0.0) << p.transpose();
  }
  EXPECT_GT(cost(100.0, Eigen::Vector2d(0.101, 0.0)), 0.0);
  EXPECT_GT(cost(100.0, Eigen::Vector2d(-0.101, 0.0)), 0.0);
  EXPECT_GT(cost(100.0, Eigen::Vector2d(0.0, 0.051)), 0.0);
  EXPECT_GT(cost(100.0, Eigen::Vector2d(0.0, -0.051)), 0.0);
  EXPECT_THROW(CenterOfPressureResidual(m, nu, s.contacts, "nope", half), std::invalid_argument);
  EXPECT_THROW(CenterOfPressureResidual(m, nu, s.contacts, "left_sole_link", Eigen::Vector2d(0, 1)),
               std::invalid_argument);
  RobotSetup solo = std::move(robotSetups()[0]);
  EXPECT_THROW(CenterOfPressureResidual(solo.model, 12, solo.contacts, "FL_FOOT", half),
               std::invalid_argument)
      << "a point contact has no centre of pressure";
}

// Lx and Lu of a cost mixing every residual and activation against finite differences of its
// value; for residuals linear in the tangent (control, joint positions and rates) the
// Gauss-Newton Hessian is exact and matches finite differences of the gradient.
TEST(Cost, GradientMatchesFiniteDifferencesOfValue) {
  std::mt19937 rng(17);
  for (RobotSetup& s : robotSetups()) {
    const Model& m = s.model;
    const StateSpace space(m);
    const Eigen::VectorXd x = randomState(m, rng);
    Knot knot(m, s.contacts);
    const int nu = knot.kd.nu, ndx = space.ndx();
    const Eigen::VectorXd u = randomUniform(rng, nu, 5.0);
    CostModel cost(m.nv, nu);
    for (Term& t : makeTerms(s, nu, x, rng))
      cost.add(t.name, std::move(t.residual), std::move(t.activation), 0.5 + cost.size() * 0.1);
    cost[cost.find("com")].active = false;  // switched-off terms count nowhere
    CostData cd = cost.createData();
    Eigen::VectorXd Lx(ndx), Lu(nu);
    Eigen::MatrixXd Lxx(ndx, ndx), Lxu(ndx, nu), Luu(nu, nu);
    const double value = cost.calcDiff(cd, knot.at(x, u), x, u, Lx, Lu, Lxx, Lxu, Luu);
    EXPECT_NEAR(value, cost.calc(cd, knot.at(x, u), x, u), 1e-12 * std::max(1.0, value));
    Eigen::VectorXd Lx_fd(ndx), Lu_fd(nu), dx = Eigen::VectorXd::Zero(ndx), xp(x.size()),
                                           xm(x.size());
    for (int j = 0; j < ndx; ++j) {
      dx[j] = kStep;
      space.integrate(x, dx, xp);
      dx[j] = -kStep;
      space.integrate(x, dx, xm);
      dx[j] = 0.0;
      Lx_fd[j] = (cost.calc(cd, knot.at(xp, u), xp, u) - cost.calc(cd, knot.at(xm, u), xm, u)) /
                 (2 * kStep);
    }
    for (int j = 0; j < nu; ++j) {
      Eigen::VectorXd up = u, um = u;
      up[j] += kStep;
      um[j] -= kStep;
      Lu_fd[j] = (cost.calc(cd, knot.at(x, up), x, up) - cost.calc(cd, knot.at(x, um), x, um)) /
                 (2 * kStep);
    }
    EXPECT_LT(relErr(Lx, Lx_fd), kTol) << s.name;
    EXPECT_LT(relErr(Lu, Lu_fd), kTol) << s.name;
    EXPECT_TRUE(Lxx.isApprox(Lxx.transpose(), 1e-12)) << s.name;

    // Linear residuals only: the Gauss-Newton Hessian is the Hessian.
    CostModel lin(m.nv, nu);
    lin.add("control", std::make_unique<ControlResidual>(m, nu, randomUniform(rng, nu, 1.0)),
            Activation::weightedQuadratic(randomUniform(rng, nu, 1.0).cwiseAbs()));
    lin.add("limits", std::make_unique<JointLimitResidual>(m, nu),
            Activation::weightedQuadratic(randomUniform(rng, 2 * (m.nv - 6), 1.0).cwiseAbs()));
    CostData ld = lin.createData();
    lin.calcDiff(ld, knot.at(x, u), x, u, Lx, Lu, Lxx, Lxu, Luu);
    Eigen::MatrixXd Lxx_fd(ndx, ndx), Luu_fd(nu, nu);
    Eigen::VectorXd Lxp(ndx), Lxm(ndx), Lup(nu), Lum(nu);
    Eigen::MatrixXd Hxx(ndx, ndx), Hxu(ndx, nu), Huu(nu, nu);
    for (int j = 0; j < ndx; ++j) {
      dx[j] = kStep;
      space.integrate(x, dx, xp);
      dx[j] = -kStep;
      space.integrate(x, dx, xm);
      dx[j] = 0.0;
      lin.calcDiff(ld, knot.at(xp, u), xp, u, Lxp, Lup, Hxx, Hxu, Huu);
      lin.calcDiff(ld, knot.at(xm, u), xm, u, Lxm, Lum, Hxx, Hxu, Huu);
      Lxx_fd.col(j) = (Lxp - Lxm) / (2 * kStep);
    }
    for (int j = 0; j < nu; ++j) {
      Eigen::VectorXd up = u, um = u;
      up[j] += kStep;
      um[j] -= kStep;
      lin.calcDiff(ld, knot.at(x, up), x, up, Lxp, Lup, Hxx, Hxu, Huu);
      lin.calcDiff(ld, knot.at(x, um), x, um, Lxm, Lum, Hxx, Hxu, Huu);
      Luu_fd.col(j) = (Lup - Lum) / (2 * kStep);
    }
    EXPECT_LT(relErr(Lxx, Lxx_fd), kTol) << s.name;
    EXPECT_LT(relErr(Luu, Luu_fd), kTol) << s.name;
  }
}

// CostModel::calcDiff skips the Jacobians and products of a term whose activation is flat there
// (zero gradient and curvature: a bounds activation inside its bounds). Its derivatives must be
// those of every term's calcDiff and dense Gauss-Newton products summed, with flat terms present:
// a friction cone so wide that it holds any force, joint limits no state reaches.
TEST(Cost, FlatTermsSkippedGiveTheSameDerivatives) {
  std::mt19937 rng(19);
  for (RobotSetup& s : robotSetups()) {
    const Model& m = s.model;
    const Eigen::VectorXd x = randomState(m, rng);
    Knot knot(m, s.contacts);
    const int nu = knot.kd.nu, ndx = 2 * m.nv;
    const Eigen::VectorXd u = randomUniform(rng, nu, 5.0);
    CostModel cost(m.nv, nu);
    for (Term& t : makeTerms(s, nu, x, rng))
      cost.add(t.name, std::move(t.residual), std::move(t.activation), 0.5 + cost.size() * 0.1);
    const std::string c0 = s.contacts[0].name;
    cost.add("flat_cone",
             std::make_unique<FrictionConeResidual>(m, nu, s.contacts, c0, 1e6,
                                                    Eigen::Matrix3d::Identity(), 0.0),
             Activation::bounds(Eigen::VectorXd::Constant(5, -1e12),
                                Eigen::VectorXd::Constant(5, 1e12), 3.0));
    cost.add("flat_limits", std::make_unique<JointLimitResidual>(m, nu),
             Activation::bounds(Eigen::VectorXd::Constant(2 * (m.nv - 6), -1e9),
                                Eigen::VectorXd::Constant(2 * (m.nv - 6), 1e9), 2.0));
    CostData cd = cost.createData();
    const KnotContext ctx = knot.at(x, u);
    Eigen::VectorXd Lx(ndx), Lu(nu);
    Eigen::MatrixXd Lxx(ndx, ndx), Lxu(ndx, nu), Luu(nu, nu);
    const double value = cost.calcDiff(cd, ctx, x, u, Lx, Lu, Lxx, Lxu, Luu);
    // The reference: every term, its Jacobians, the dense default products.
    Eigen::VectorXd Lx_ref = Eigen::VectorXd::Zero(ndx), Lu_ref = Eigen::VectorXd::Zero(nu);
    Eigen::MatrixXd Lxx_ref = Eigen::MatrixXd::Zero(ndx, ndx),
                    Lxu_ref = Eigen::MatrixXd::Zero(ndx, nu),
                    Luu_ref = Eigen::MatrixXd::Zero(nu, nu);
    double value_ref = 0.0;
    int flat = 0;
    for (int i = 0; i < cost.size(); ++i) {
      const CostTerm& t = cost[i];
      auto d = t.residual->createData();
      t.residual->calc(*d, ctx, x, u);
      t.residual->calcDiff(*d, ctx, x, u);
      const int dim = t.residual->dim();
      Eigen::VectorXd g(dim), h(dim);
      value_ref += t.weight * t.activation.derivatives(d->r, g, h);
      if (g.isZero(0.0) && h.isZero(0.0)) ++flat;
      const int nx = stateColumns(*t.residual);
      Eigen::MatrixXd Rx = Eigen::MatrixXd::Zero(dim, ndx), Ru = Eigen::MatrixXd::Zero(dim, nu);
      Rx.leftCols(nx) = d->Rx.leftCols(nx);
      if (hasControl(*t.residual)) Ru = d->Ru;
      g *= t.weight;
      h *= t.weight;
      Lx_ref += Rx.transpose() * g;
      Lu_ref += Ru.transpose() * g;
      Lxx_ref += Rx.transpose() * h.asDiagonal() * Rx;
      Lxu_ref += Rx.transpose() * h.asDiagonal() * Ru;
      Luu_ref += Ru.transpose() * h.asDiagonal() * Ru;
    }
    EXPECT_GE(flat, 2) << s.name << ": the flat terms must be flat";
    EXPECT_NEAR(value, value_ref, 1e-12 * std::max(1.0, std::abs(value_ref))) << s.name;
    EXPECT_LT(relErr(Lx, Lx_ref), 1e-12) << s.name;
    EXPECT_LT(relErr(Lu, Lu_ref), 1e-12) << s.name;
    EXPECT_LT(relErr(Lxx, Lxx_ref), 1e-12) << s.name;
    EXPECT_LT(relErr(Lxu, Lxu_ref), 1e-12) << s.name;
    EXPECT_LT(relErr(Luu, Luu_ref), 1e-12) << s.name;
  }
}

// Setters rewrite references in place; wrong sizes and bad values throw.
TEST(Residuals, ReferencesAndBadArguments) {
  RobotSetup s = std::move(robotSetups()[0]);
  const Model& m = s.model;
  const int nu = m.nv - 6;
  try {
    FramePlacementResidual r(m, nu, "NO_SUCH_FRAME");
    ADD_FAILURE() << "unknown frame accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("NO_SUCH_FRAME"), std::string::npos) << e.what();
  }
  EXPECT_THROW(FrameTranslationResidual(m, nu, "nope"), std::invalid_argument);
  EXPECT_THROW(FrameRotationResidual(m, nu, "nope"), std::invalid_argument);
  EXPECT_THROW(FrameVelocityResidual(m, nu, "nope", ReferenceFrame::Local), std::invalid_argument);
  EXPECT_THROW(FrameVelocityResidual(m, nu, "FL_FOOT", ReferenceFrame::World),
               std::invalid_argument);
  EXPECT_THROW(StateResidual(m, nu, Eigen::VectorXd::Zero(m.nq)), std::invalid_argument);
  EXPECT_THROW(ControlResidual(m, nu, Eigen::VectorXd::Zero(nu + 1)), std::invalid_argument);
  try {
    ContactForceResidual r(m, nu, s.contacts, "NO_SUCH_CONTACT");
    ADD_FAILURE() << "unknown contact accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("NO_SUCH_CONTACT"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ContactForceResidual(m, nu, s.contacts, "FL_FOOT", Eigen::VectorXd::Zero(6)),
               std::invalid_argument);
  EXPECT_THROW(FrictionConeResidual(m, nu, s.contacts, "nope", 0.7), std::invalid_argument);
  EXPECT_THROW(FrictionConeResidual(m, nu, s.contacts, "FL_FOOT", 0.0), std::invalid_argument);
  EXPECT_THROW(
      FrictionConeResidual(m, nu, s.contacts, "FL_FOOT", 0.7, 2.0 * Eigen::Matrix3d::Identity()),
      std::invalid_argument);
  EXPECT_THROW(
      FrictionConeResidual(m, nu, s.contacts, "FL_FOOT", 0.7, Eigen::Matrix3d::Identity(), -1.0),
      std::invalid_argument);
  EXPECT_THROW(JointLimitResidual::activation(m, 1.0, 0.0), std::invalid_argument);

  StateResidual st(m, nu);
  EXPECT_THROW(st.setReference(Eigen::VectorXd::Zero(3)), std::invalid_argument);
  Eigen::VectorXd x_ref = Eigen::VectorXd::Zero(m.nq + m.nv);
  x_ref.head(m.nq) = neutral(m);
  x_ref[0] = 0.3;
  st.setReference(x_ref);
  EXPECT_EQ(st.reference(), x_ref);
  // The joint-limit activation carries the model's limits on the actuated joints.
  const Activation lim = JointLimitResidual::activation(m);
  ASSERT_EQ(lim.dim(), 2 * nu);
  EXPECT_EQ(lim.lower.head(nu), m.lowerPositionLimit.tail(nu));
  EXPECT_EQ(lim.upper.head(nu), m.upperPositionLimit.tail(nu));
  EXPECT_EQ(lim.upper.tail(nu), m.velocityLimit.tail(nu));
  EXPECT_EQ(lim.lower.tail(nu), -m.velocityLimit.tail(nu));
}

}  // namespace test_residuals
}  // namespace stride
