// KKT contact dynamics, impulse dynamics and the knot dynamics of eq. 11: every Jacobian against
// central finite differences on the manifold, physical laws, rank-deficient contact sets with
// damping, and bad input.

#include <gtest/gtest.h>

#include <random>

#include "config/robot_config.hpp"
#include "multibody/random_tree.hpp"
#include "solver/contact/knot_dynamics.hpp"
#include "solver/multibody/aba.hpp"
#include "solver/multibody/aba_derivatives.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/rnea_derivatives.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace test_contact_dynamics {

constexpr double kStep = 1e-6;
constexpr double kTol = 1e-6;
// The contact, impulse and knot derivatives against central differences (undamped cases): the
// differences' rounding depends on the compiler's instruction choices. In
// ContactDynamics.DerivativesMatchFiniteDifferences, talos' 2 soles (∂v̇/∂q, second sample) gives
// 8.2e-7 with gcc 12 -O3 and 1.01e-6 with clang 14 -O2 and the sanitizers; every other case and
// block stays under 6.8e-7 with both.
constexpr double kContactTol = 2e-6;

struct Case {
  std::string name;
  Model model;
  ContactSet contacts;
  double damping = 0.0;
  // Finite differences lose ~eps |λ| / h, and with damping μ the null-space forces are ~1/μ:
  // the damped (rank-deficient) cases get a tolerance scaled by that conditioning.
  double tol() const { return damping > 0 ? 1e-4 : kContactTol; }
};

// max|a - b| / max(1, max|b|)
double relErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return 1e9;
  if (b.size() == 0) return 0.0;
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

Model shared(const std::string& urdf, RootJoint root = RootJoint::FreeFlyer) {
  return buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/" + urdf, root);
}

std::vector<Case> cases() {
  std::vector<Case> out;
  {
    Case c{"solo12 4 points LOCAL", shared("solo12/solo12.urdf"), {}, 0.0};
    for (const char* f : {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"})
      c.contacts.add(c.model, f, 3);
    out.push_back(std::move(c));
  }
  {
    Case c{"solo12 points LWA + Baumgarte", shared("solo12/solo12.urdf"), {}, 0.0};
    for (const char* f : {"FL_FOOT", "HR_FOOT"})
      c.contacts.add(c.model, f, 3, ReferenceFrame::LocalWorldAligned, 30.0, 5.0);
    c.contacts.setReference(
        0, SE3(exp3(Eigen::Vector3d(0.1, 0.2, -0.1)), Eigen::Vector3d(0.1, 0.2, 0.0)));
    c.contacts.setReference(1, SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.2, -0.1, 0.05)));
    out.push_back(std::move(c));
  }
  {
    Case c{"talos 2 soles", shared("talos/talos_reduced.urdf"), {}, 0.0};
    c.contacts.add(c.model, "left_sole_link", 6);
    c.contacts.add(c.model, "right_sole_link", 6, ReferenceFrame::LocalWorldAligned, 10.0, 2.0);
    c.contacts.setReference(
        1, SE3(exp3(Eigen::Vector3d(0.05, -0.1, 0.3)), Eigen::Vector3d(0.0, -0.1, 0.02)));
    out.push_back(std::move(c));
  }
  {
    // Rank deficient: two surface contacts on the same sole (the paper's overlapping feet). The
    // damping is large enough for finite differences to resolve the 1/μ-sized null-space forces.
    Case c{"talos overlapping soles, damped", shared("talos/talos_reduced.urdf"), {}, 1e-3};
    c.contacts.add(c.model, "left_sole_link", 6);
    c.contacts.add(c.model, "left_sole_link", 6);
    out.push_back(std::move(c));
  }
  {
    // Rank deficient: four collinear point contacts on one body.
    Case c{"talos 4 collinear points, damped", shared("talos/talos_reduced.urdf"), {}, 1e-3};
    const int sole = c.model.getFrameId("left_sole_link");
    for (int k = 0; k < 4; ++k) {
      Frame f = c.model.frames[sole];
      f.name = "line_" + std::to_string(k);
      f.type = FrameType::Operational;
      f.parentFrame = sole;
      f.placement = c.model.frames[sole].placement *
                    SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.05 * k - 0.05, 0, 0));
      c.model.addFrame(f);
      c.contacts.add(c.model, f.name, 3);
    }
    out.push_back(std::move(c));
  }
  {
    Robot quad = loadRobot(STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml");
    Case c{"stride_quad 4 points", quad.model, {}, 0.0};
    for (const auto& s : quad.contacts) c.contacts.add(c.model, s.frame, s.dim);
    out.push_back(std::move(c));
  }
  {
    Robot hum = loadRobot(STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml");
    Case c{"stride_humanoid 2 soles", hum.model, {}, 0.0};
    for (const auto& s : hum.contacts) c.contacts.add(c.model, s.frame, s.dim);
    c.contacts.setActive(1, false);  // single support
    out.push_back(std::move(c));
  }
  {
    Case c{"ur5 tool point (fixed base)", shared("ur5/ur5_robot.urdf", RootJoint::Fixed), {}, 0.0};
    c.contacts.add(c.model, "tool0", 3, ReferenceFrame::LocalWorldAligned, 0.0, 3.0);
    out.push_back(std::move(c));
  }
  // Random trees with a free-flyer: a surface contact (world-aligned forces, Baumgarte) on a frame
  // of one branch and, when the tree has one, a point contact on a frame of a different branch.
  std::mt19937 rng(2024);
  for (int t = 0; t < 6; ++t) {
    Case c{"random tree " + std::to_string(t), makeRandomTree(rng, 8 + 2 * t, true), {}, 0.0};
    const Model& m = c.model;
    auto onPath = [&](int a, int b) {  // a is b or one of its ancestors
      for (int j = b; j >= 0; j = j > 0 ? m.joints[j].parent : -1)
        if (j == a) return true;
      return false;
    };
    int surface = -1, point = -1;
    for (int f = m.nframes() - 1; f > 0 && surface < 0; --f)
      if (m.frames[f].parentJoint > 1) surface = f;
    const int js = m.frames[surface].parentJoint;
    for (int f = 1; f < m.nframes() && point < 0; ++f) {
      const int jp = m.frames[f].parentJoint;
      if (jp > 1 && !onPath(jp, js) && !onPath(js, jp)) point = f;
    }
    // A point contact whose own branch has fewer than 3 independent dofs (or parallel axes) makes
    // Jc rank-deficient: keep it only when the pair solves without damping.
    for (const bool with_point : {true, false}) {
      if (with_point && point < 0) continue;
      ContactSet set;
      set.add(m, m.frames[surface].name, 6, ReferenceFrame::LocalWorldAligned, 20.0, 4.0);
      set.setReference(0,
                       SE3(exp3(Eigen::Vector3d(0.1, -0.2, 0.1)), Eigen::Vector3d(0.1, 0.0, 0.2)));
      if (with_point) set.add(m, m.frames[point].name, 3);
      Data d(m);
      ContactData cd(m, set);
      const Eigen::VectorXd q = randomConfiguration(m, rng), z = Eigen::VectorXd::Zero(m.nv);
      if (contactDynamics(m, d, set, cd, q, z, z) != ContactStatus::Ok) continue;
      c.contacts = set;
      break;
    }
    if (c.contacts.size() == 0) ADD_FAILURE() << c.name << ": no regular contact set";
    out.push_back(std::move(c));
  }
  return out;
}

struct State {
  Eigen::VectorXd q, v, tau;
};

State randomState(const Model& model, std::mt19937& rng) {
  State s;
  s.q = randomConfiguration(model, rng);
  std::uniform_real_distribution<double> u(-1, 1);
  s.v = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
  s.tau = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return 5 * u(rng); });
  if (model.hasFreeFlyer()) s.tau.head<6>().setZero();
  return s;
}

// Central differences of f (an output vector of size m) along the tangent directions of q, the
// directions of v and those of tau.
template <typename F>
Eigen::MatrixXd fdQ(const Model& model, const Eigen::VectorXd& q, long m, F f) {
  Eigen::MatrixXd J(m, model.nv);
  for (int k = 0; k < model.nv; ++k) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(model.nv);
    e[k] = kStep;
    J.col(k) = (f(integrate(model, q, e)) - f(integrate(model, q, -e))) / (2 * kStep);
  }
  return J;
}
template <typename F>
Eigen::MatrixXd fdVec(const Eigen::VectorXd& x, long m, F f) {
  Eigen::MatrixXd J(m, x.size());
  for (int k = 0; k < x.size(); ++k) {
    Eigen::VectorXd xp = x, xm = x;
    xp[k] += kStep;
    xm[k] -= kStep;
    J.col(k) = (f(xp) - f(xm)) / (2 * kStep);
  }
  return J;
}

TEST(ContactDynamics, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(3);
  for (Case& c : cases()) {
    Data data(c.model);
    ContactData cd(c.model, c.contacts);
    for (int sample = 0; sample < 2; ++sample) {
      const State s = randomState(c.model, rng);
      ASSERT_EQ(
          contactDynamicsDerivatives(c.model, data, c.contacts, cd, s.q, s.v, s.tau, c.damping),
          ContactStatus::Ok)
          << c.name;
      const int nc = cd.nc, nv = c.model.nv;
      const Eigen::MatrixXd ddq_dq = cd.ddq_dq, ddq_dv = cd.ddq_dv, ddq_dtau = cd.ddq_dtau;
      const Eigen::MatrixXd l_dq = cd.lambda_dq.topRows(nc), l_dv = cd.lambda_dv.topRows(nc),
                            l_dtau = cd.lambda_dtau.topRows(nc);
      Data d2(c.model);
      ContactData c2(c.model, c.contacts);
      auto out = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                     const Eigen::VectorXd& tau) {
        EXPECT_EQ(contactDynamics(c.model, d2, c.contacts, c2, q, v, tau, c.damping),
                  ContactStatus::Ok);
        Eigen::VectorXd o(nv + nc);
        o << c2.ddq, c2.lambda.head(nc);
        return o;
      };
      const Eigen::MatrixXd Fq =
          fdQ(c.model, s.q, nv + nc, [&](const Eigen::VectorXd& q) { return out(q, s.v, s.tau); });
      const Eigen::MatrixXd Fv =
          fdVec(s.v, nv + nc, [&](const Eigen::VectorXd& v) { return out(s.q, v, s.tau); });
      const Eigen::MatrixXd Ft =
          fdVec(s.tau, nv + nc, [&](const Eigen::VectorXd& t) { return out(s.q, s.v, t); });
      EXPECT_LT(relErr(ddq_dq, Fq.topRows(nv)), c.tol()) << c.name << " ddq/dq";
      EXPECT_LT(relErr(ddq_dv, Fv.topRows(nv)), c.tol()) << c.name << " ddq/dv";
      EXPECT_LT(relErr(ddq_dtau, Ft.topRows(nv)), c.tol()) << c.name << " ddq/dtau";
      EXPECT_LT(relErr(l_dq, Fq.bottomRows(nc)), c.tol()) << c.name << " lambda/dq";
      EXPECT_LT(relErr(l_dv, Fv.bottomRows(nc)), c.tol()) << c.name << " lambda/dv";
      EXPECT_LT(relErr(l_dtau, Ft.bottomRows(nc)), c.tol()) << c.name << " lambda/dtau";
    }
  }
}

// The knot's path (τ columns from tau_first on) gives exactly the full computation's columns and
// leaves the others alone; the *FromKinematics variants equal their full counterparts after crba.
TEST(ContactDynamics, PartialTauColumnsAndKinematicsReuse) {
  std::mt19937 rng(11);
  for (Case& c : cases()) {
    const Model& m = c.model;
    const State s = randomState(m, rng);
    Data d1(m), d2(m);
    ContactData full(m, c.contacts), part(m, c.contacts);
    ASSERT_EQ(contactDynamicsDerivatives(m, d1, c.contacts, full, s.q, s.v, s.tau, c.damping),
              ContactStatus::Ok)
        << c.name;
    const int first = m.hasFreeFlyer() ? 6 : 0, cols = m.nv - first;
    part.ddq_dtau.setConstant(7.0);
    part.lambda_dtau.setConstant(7.0);
    ASSERT_EQ(
        contactDynamicsDerivatives(m, d2, c.contacts, part, s.q, s.v, s.tau, c.damping, first),
        ContactStatus::Ok);
    const int nc = full.nc;
    EXPECT_LT(relErr(part.ddq_dtau.rightCols(cols), full.ddq_dtau.rightCols(cols)), 1e-12);
    EXPECT_LT(relErr(part.lambda_dtau.topRows(nc).rightCols(cols),
                     full.lambda_dtau.topRows(nc).rightCols(cols)),
              1e-12);
    EXPECT_TRUE((part.ddq_dtau.leftCols(first).array() == 7.0).all());
    EXPECT_TRUE((part.lambda_dtau.leftCols(first).array() == 7.0).all());
    EXPECT_LT(relErr(part.ddq_dq, full.ddq_dq), 1e-12);
    EXPECT_LT(relErr(part.lambda_dv.topRows(nc), full.lambda_dv.topRows(nc)), 1e-12);

    Data a(m), b(m);
    const Eigen::VectorXd nle = nonLinearEffects(m, a, s.q, s.v);
    crba(m, b, s.q);
    EXPECT_LT(relErr(nonLinearEffectsFromKinematics(m, b, s.v), nle), 1e-12) << c.name;
    std::vector<Vector6d> fext(static_cast<size_t>(m.njoints()));
    for (auto& f : fext) f = Vector6d::Random();
    computeRNEADerivatives(m, a, s.q, s.v, s.tau, fext, true);
    crba(m, b, s.q);
    computeRNEADerivativesFromKinematics(m, b, s.v, s.tau, fext, true);
    EXPECT_LT(relErr(b.dtau_dq, a.dtau_dq), 1e-12) << c.name;
    EXPECT_LT(relErr(b.dtau_dv, a.dtau_dv), 1e-12) << c.name;
    EXPECT_LT(relErr(b.tau, a.tau), 1e-12) << c.name;
  }
}

TEST(ImpulseDynamics, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(5);
  for (Case& c : cases()) {
    Data data(c.model);
    ContactData cd(c.model, c.contacts);
    for (double restitution : {0.0, 0.3}) {
      const State s = randomState(c.model, rng);
      ASSERT_EQ(impulseDynamicsDerivatives(c.model, data, c.contacts, cd, s.q, s.v, restitution,
                                           c.damping),
                ContactStatus::Ok)
          << c.name;
      const int nc = cd.nc, nv = c.model.nv;
      const Eigen::MatrixXd vq = cd.ddq_dq, vv = cd.ddq_dv;
      const Eigen::MatrixXd lq = cd.lambda_dq.topRows(nc), lv = cd.lambda_dv.topRows(nc);
      Data d2(c.model);
      ContactData c2(c.model, c.contacts);
      auto out = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
        EXPECT_EQ(impulseDynamics(c.model, d2, c.contacts, c2, q, v, restitution, c.damping),
                  ContactStatus::Ok);
        Eigen::VectorXd o(nv + nc);
        o << c2.v_after, c2.impulses.head(nc);
        return o;
      };
      const Eigen::MatrixXd Fq =
          fdQ(c.model, s.q, nv + nc, [&](const Eigen::VectorXd& q) { return out(q, s.v); });
      const Eigen::MatrixXd Fv =
          fdVec(s.v, nv + nc, [&](const Eigen::VectorXd& v) { return out(s.q, v); });
      EXPECT_LT(relErr(vq, Fq.topRows(nv)), c.tol()) << c.name << " v+/dq";
      EXPECT_LT(relErr(vv, Fv.topRows(nv)), c.tol()) << c.name << " v+/dv-";
      EXPECT_LT(relErr(lq, Fq.bottomRows(nc)), c.tol()) << c.name << " impulse/dq";
      EXPECT_LT(relErr(lv, Fv.bottomRows(nc)), c.tol()) << c.name << " impulse/dv-";
    }
  }
}

TEST(KnotDynamics, JacobiansMatchFiniteDifferences) {
  std::mt19937 rng(9);
  const double dt = 0.01;
  for (Case& c : cases()) {
    Data data(c.model);
    KnotData kd(c.model, c.contacts);
    const State s = randomState(c.model, rng);
    const Eigen::VectorXd u = s.tau.tail(kd.nu);
    ASSERT_EQ(knotDynamicsDerivatives(c.model, data, c.contacts, kd, s.q, s.v, u, dt, c.damping),
              ContactStatus::Ok);
    const int nv = c.model.nv, nc = kd.contact.nc;
    const Eigen::VectorXd q_next = kd.q_next;
    const Eigen::MatrixXd Fx = kd.Fx, Fu = kd.Fu, Gx = kd.Gx.topRows(nc), Gu = kd.Gu.topRows(nc);
    Data d2(c.model);
    KnotData k2(c.model, c.contacts);
    // Output in the tangent space: [q⁺ ⊖ q⁺_0; v⁺; λ].
    auto out = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& uu) {
      EXPECT_EQ(knotDynamics(c.model, d2, c.contacts, k2, q, v, uu, dt, c.damping),
                ContactStatus::Ok);
      Eigen::VectorXd o(2 * nv + nc);
      o << difference(c.model, q_next, k2.q_next), k2.v_next, k2.contact.lambda.head(nc);
      return o;
    };
    const Eigen::MatrixXd Nq =
        fdQ(c.model, s.q, 2 * nv + nc, [&](const Eigen::VectorXd& q) { return out(q, s.v, u); });
    const Eigen::MatrixXd Nv =
        fdVec(s.v, 2 * nv + nc, [&](const Eigen::VectorXd& v) { return out(s.q, v, u); });
    const Eigen::MatrixXd Nu =
        fdVec(u, 2 * nv + nc, [&](const Eigen::VectorXd& uu) { return out(s.q, s.v, uu); });
    EXPECT_LT(relErr(Fx.leftCols(nv), Nq.topRows(2 * nv)), c.tol()) << c.name << " Fx (q)";
    EXPECT_LT(relErr(Fx.rightCols(nv), Nv.topRows(2 * nv)), c.tol()) << c.name << " Fx (v)";
    EXPECT_LT(relErr(Fu, Nu.topRows(2 * nv)), c.tol()) << c.name << " Fu";
    EXPECT_LT(relErr(Gx.leftCols(nv), Nq.bottomRows(nc)), c.tol()) << c.name << " Gx (q)";
    EXPECT_LT(relErr(Gx.rightCols(nv), Nv.bottomRows(nc)), c.tol()) << c.name << " Gx (v)";
    EXPECT_LT(relErr(Gu, Nu.bottomRows(nc)), c.tol()) << c.name << " Gu";
  }
}

TEST(Derivatives, RneaAndAbaMatchFiniteDifferences) {
  std::mt19937 rng(17);
  for (Case& c : cases()) {
    const Model& model = c.model;
    Data data(model), d2(model);
    const State s = randomState(model, rng);
    const Eigen::VectorXd a = s.tau / 5.0;
    const int nv = model.nv;
    computeRNEADerivatives(model, data, s.q, s.v, a);
    const Eigen::MatrixXd tq = data.dtau_dq, tv = data.dtau_dv;
    auto tau = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
      return Eigen::VectorXd(rnea(model, d2, q, v, a));
    };
    EXPECT_LT(
        relErr(tq, fdQ(model, s.q, nv, [&](const Eigen::VectorXd& q) { return tau(q, s.v); })),
        kTol)
        << c.name;
    EXPECT_LT(relErr(tv, fdVec(s.v, nv, [&](const Eigen::VectorXd& v) { return tau(s.q, v); })),
              kTol)
        << c.name;
    // Realistic torques: on solo12's 0.1 kg legs ±5 N·m gives accelerations in the thousands, and
    // finite differences lose eps |v̇| / h to rounding (the reference check covers the exact
    // values).
    const Eigen::VectorXd tau_small = 0.2 * s.tau;
    computeABADerivatives(model, data, s.q, s.v, tau_small);
    const Eigen::MatrixXd aq = data.ddq_dq, av = data.ddq_dv, at = data.Minv;
    auto acc = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& t) {
      return Eigen::VectorXd(aba(model, d2, q, v, t));
    };
    EXPECT_LT(relErr(aq, fdQ(model, s.q, nv,
                             [&](const Eigen::VectorXd& q) { return acc(q, s.v, tau_small); })),
              kTol)
        << c.name;
    EXPECT_LT(relErr(av, fdVec(s.v, nv,
                               [&](const Eigen::VectorXd& v) { return acc(s.q, v, tau_small); })),
              kTol)
        << c.name;
    EXPECT_LT(relErr(at, fdVec(tau_small, nv,
                               [&](const Eigen::VectorXd& t) { return acc(s.q, s.v, t); })),
              kTol)
        << c.name;
  }
}

// A contact set without any contact (the astronaut's, in zero gravity): the contact dynamics and
// their derivatives are ABA's. Its workspaces have no rows (data() null): blocks of them at a
// column offset were undefined behaviour, caught by UndefinedBehaviorSanitizer
// (tools/test.sh --sanitize).
TEST(ContactDynamics, NoContactAtAllIsAbaAndItsDerivatives) {
  std::mt19937 rng(5);
  const Robot quad = loadRobot(STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml");
  const Model& model = quad.model;
  const ContactSet none;
  Data data(model), ref(model);
  ContactData cd(model, none);
  const State s = randomState(model, rng);
  ASSERT_EQ(contactDynamicsDerivatives(model, data, none, cd, s.q, s.v, s.tau), ContactStatus::Ok);
  EXPECT_EQ(cd.nc, 0);
  computeABADerivatives(model, ref, s.q, s.v, s.tau);
  EXPECT_LT(relErr(cd.ddq, ref.ddq), 1e-10);
  EXPECT_LT(relErr(cd.ddq_dq, ref.ddq_dq), 1e-10);
  EXPECT_LT(relErr(cd.ddq_dv, ref.ddq_dv), 1e-10);
  EXPECT_LT(relErr(cd.ddq_dtau, ref.Minv), 1e-10);
  // The knot's path: the actuated columns only.
  ASSERT_EQ(contactDynamicsDerivatives(model, data, none, cd, s.q, s.v, s.tau, 0.0, 6),
            ContactStatus::Ok);
  EXPECT_LT(relErr(cd.ddq_dtau.rightCols(model.nv - 6), ref.Minv.rightCols(model.nv - 6)), 1e-10);
}

TEST(ContactDynamics, NewtonForTheWholeBody) {
  // Σ contact forces = m (c̈ - g), with c̈ measured by differentiating the CoM velocity along the
  // solved motion, an independent route from the KKT solve.
  std::mt19937 rng(11);
  for (Case& c : cases()) {
    if (!c.model.hasFreeFlyer() || c.damping > 0) continue;
    Data data(c.model);
    ContactData cd(c.model, c.contacts);
    const State s = randomState(c.model, rng);
    ASSERT_EQ(contactDynamics(c.model, data, c.contacts, cd, s.q, s.v, s.tau), ContactStatus::Ok);
    const Eigen::VectorXd ddq = cd.ddq;
    // Total external force in the world frame.
    framesForwardKinematics(c.model, data, s.q);
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    int r = 0;
    for (int k = 0; k < c.contacts.size(); ++k) {
      if (!c.contacts.isActive(k)) continue;
      const ContactModel& cm = c.contacts[k];
      const Eigen::Vector3d f = cd.lambda.segment<3>(r);
      force += cm.forces == ReferenceFrame::Local ? Eigen::Vector3d(data.oMf[cm.frame].R * f) : f;
      r += cm.dim;
    }
    const double h = 1e-6, m = c.model.totalMass();
    auto vcom = [&](double t) {
      Eigen::VectorXd q = integrate(c.model, s.q, t * s.v + 0.5 * t * t * ddq);
      Eigen::VectorXd v = s.v + t * ddq;
      // v must be the velocity of the curve q(t) in the base frame: on SE(3) that is the right
      // Jacobian of the exponential applied to the tangent velocity.
      Eigen::MatrixXd Jr(c.model.nv, c.model.nv);
      dIntegrate(c.model, s.q, t * s.v + 0.5 * t * t * ddq, Jr, ArgumentPosition::Second);
      v = Jr * v;
      centerOfMass(c.model, data, q, v);
      return Eigen::Vector3d(data.vcom);
    };
    const Eigen::Vector3d cdd = (vcom(h) - vcom(-h)) / (2 * h);
    EXPECT_LT((force - m * (cdd - c.model.gravity)).norm(), 1e-5 * std::max(1.0, force.norm()))
        << c.name;
  }
}

TEST(ContactDynamics, StaticEquilibriumCarriesTheWeight) {
  for (const char* name : {"stride_quad", "stride_humanoid"}) {
    const Robot robot =
        loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/" + name + "/" + name + ".yaml");
    const Model& model = robot.model;
    ContactSet contacts;
    for (const auto& s : robot.contacts)
      contacts.add(model, s.frame, s.dim, ReferenceFrame::LocalWorldAligned);
    Data data(model);
    ContactData cd(model, contacts);
    const Eigen::VectorXd v = Eigen::VectorXd::Zero(model.nv);
    // Torques of a static equilibrium: g(q) = Jc^T λ + [0; u]; the base rows fix λ (least norm).
    ASSERT_EQ(contactDynamics(model, data, contacts, cd, robot.default_q, v,
                              Eigen::VectorXd::Zero(model.nv)),
              ContactStatus::Ok);
    const int nc = cd.nc;
    const Eigen::MatrixXd Jc = cd.Jc.topRows(nc);
    const Eigen::VectorXd g = computeGeneralizedGravity(model, data, robot.default_q);
    const Eigen::VectorXd lam =
        Jc.leftCols(6).transpose().completeOrthogonalDecomposition().solve(g.head(6));
    Eigen::VectorXd tau = g - Jc.transpose() * lam;
    EXPECT_LT(tau.head(6).norm(), 1e-9);
    tau.head(6).setZero();
    ASSERT_EQ(contactDynamics(model, data, contacts, cd, robot.default_q, v, tau),
              ContactStatus::Ok);
    EXPECT_LT(cd.ddq.norm(), 1e-8) << name;
    double vertical = 0;
    for (int r = 0; r < nc; r += robot.contacts[0].dim) vertical += cd.lambda[r + 2];
    EXPECT_NEAR(vertical, -model.totalMass() * model.gravity.z(), 1e-8 * model.totalMass()) << name;
  }
}

TEST(ImpulseDynamics, ContactPointsStop) {
  std::mt19937 rng(13);
  for (Case& c : cases()) {
    Data data(c.model);
    ContactData cd(c.model, c.contacts);
    const State s = randomState(c.model, rng);
    ASSERT_EQ(impulseDynamics(c.model, data, c.contacts, cd, s.q, s.v, 0.0, c.damping),
              ContactStatus::Ok);
    const double scale = std::max(1.0, s.v.norm());
    // Damping leaves a residual velocity of the order of the damping.
    EXPECT_LT((cd.Jc.topRows(cd.nc) * cd.v_after).norm(), (c.damping > 0 ? 1e-1 : 1e-10) * scale)
        << c.name;
  }
}

TEST(ContactDynamics, BadInput) {
  Model model = shared("solo12/solo12.urdf");
  ContactSet contacts;
  EXPECT_THROW(contacts.add(model, "NO_SUCH_FOOT", 3), std::invalid_argument);
  EXPECT_THROW(contacts.add(model, "FL_FOOT", 4), std::invalid_argument);
  EXPECT_THROW(contacts.add(model, "FL_FOOT", 3, ReferenceFrame::World), std::invalid_argument);
  contacts.add(model, "FL_FOOT", 6);
  contacts.add(model, "FL_FOOT", 6);  // the same surface twice: K is singular without damping
  Data data(model);
  ContactData cd(model, contacts);
  std::mt19937 rng(1);
  State s = randomState(model, rng);
  EXPECT_EQ(contactDynamics(model, data, contacts, cd, s.q, s.v, s.tau), ContactStatus::Singular);
  EXPECT_TRUE(cd.ddq.allFinite());
  EXPECT_EQ(contactDynamics(model, data, contacts, cd, s.q, s.v, s.tau, 1e-8), ContactStatus::Ok);
  s.v[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(contactDynamics(model, data, contacts, cd, s.q, s.v, s.tau, 1e-8),
            ContactStatus::NonFinite);
  EXPECT_TRUE(cd.ddq.allFinite() && cd.lambda.allFinite());
  EXPECT_EQ(impulseDynamics(model, data, contacts, cd, s.q, s.v), ContactStatus::NonFinite);
  EXPECT_THROW(contactDynamics(model, data, contacts, cd, s.v, s.v, s.tau), std::invalid_argument);
  // Switching contacts on and off changes the active dimension without reallocating.
  EXPECT_TRUE(contacts.setActive(1, false));
  EXPECT_EQ(contacts.nc(), 6);
  EXPECT_EQ(contacts.maxNc(), 12);
  EXPECT_FALSE(contacts.setActive(7, false));
  // A set that grew after its workspace was built is refused, not written out of bounds.
  contacts.add(model, "HR_FOOT", 6);
  EXPECT_THROW(
      contactDynamics(model, data, contacts, cd, s.q, Eigen::VectorXd::Zero(model.nv), s.tau),
      std::invalid_argument);
  // A knot with a non-finite time step is flagged.
  ContactSet one;
  one.add(model, "FL_FOOT", 3);
  KnotData kd(model, one);
  EXPECT_EQ(knotDynamics(model, data, one, kd, s.q, Eigen::VectorXd::Zero(model.nv),
                         Eigen::VectorXd::Zero(kd.nu), std::numeric_limits<double>::quiet_NaN()),
            ContactStatus::NonFinite);
  // A frame fixed to the world constrains nothing.
  const Model ur5 = shared("ur5/ur5_robot.urdf", RootJoint::Fixed);
  ContactSet fixed;
  EXPECT_THROW(fixed.add(ur5, "base_link", 3), std::invalid_argument);
}

TEST(ContactDynamics, RedundantPointContactsAreAlwaysSingular) {
  // The same point twice: K is exactly singular, but rounding often leaves a tiny positive pivot
  // that a plain LLT accepts, splitting the force arbitrarily. It must be reported every time.
  const Model model = shared("solo12/solo12.urdf");
  ContactSet contacts;
  contacts.add(model, "FL_FOOT", 3);
  contacts.add(model, "FL_FOOT", 3);
  Data data(model);
  ContactData cd(model, contacts);
  std::mt19937 rng(1);
  int singular = 0;
  for (int k = 0; k < 300; ++k) {
    const State s = randomState(model, rng);
    singular +=
        contactDynamics(model, data, contacts, cd, s.q, s.v, s.tau) == ContactStatus::Singular;
  }
  EXPECT_EQ(singular, 300);
}

TEST(ContactDynamics, MasslessBodyIsReportedAsSuch) {
  // A moving joint carrying no inertia makes M singular: flagged, not reported as a contact issue.
  Model model = shared("ur5/ur5_robot.urdf", RootJoint::Fixed);
  const int leaf = model.addJoint(model.getJointId("wrist_3_joint"), JointType::Revolute,
                                  SE3::Identity(), "leaf", Eigen::Vector3d::UnitX());
  Frame f;
  f.name = "leaf_point";
  f.parentJoint = leaf;
  f.placement = SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0.1, 0));
  model.addFrame(f);
  ContactSet contacts;
  contacts.add(model, "leaf_point", 3);
  Data data(model);
  ContactData cd(model, contacts);
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(model.nv);
  EXPECT_EQ(
      contactDynamics(model, data, contacts, cd, Eigen::VectorXd::Constant(model.nq, 0.3), z, z),
      ContactStatus::SingularMassMatrix);
  EXPECT_TRUE(cd.ddq.allFinite());
}

}  // namespace test_contact_dynamics
}  // namespace stride
