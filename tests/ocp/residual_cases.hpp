#pragma once
// Shared by test_residuals and test_ocp_no_alloc: the robots with their contact sets, a knot that
// builds the residuals' context at any (x, u) (contact dynamics and derivatives, then the
// kinematics the context promises), and one residual of every kind with references drawn near a
// given state. Header-only.

#include <memory>
#include <random>
#include <string>
#include <vector>

#include "solver/contact/knot_dynamics.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/urdf.hpp"
#include "solver/ocp/action.hpp"
#include "solver/ocp/residual_com.hpp"
#include "solver/ocp/residual_contact.hpp"
#include "solver/ocp/residual_cop.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"

namespace stride {
namespace ocp_test {

struct RobotSetup {
  std::string name;
  Model model;
  ContactSet contacts;
  std::string frame_a, frame_b;  // frames the frame residuals track
};

// solo12 on four point feet (LOCAL and world-aligned forces mixed), talos_reduced on two soles
// (6D, one of each force frame, with Baumgarte terms).
inline std::vector<RobotSetup> robotSetups() {
  std::vector<RobotSetup> out;
  {
    RobotSetup s{
        "solo12",
        buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/solo12/solo12.urdf", RootJoint::FreeFlyer),
        {},
        "FL_FOOT",
        "HR_LOWER_LEG"};
    s.contacts.add(s.model, "FL_FOOT", 3, ReferenceFrame::LocalWorldAligned);
    s.contacts.add(s.model, "FR_FOOT", 3, ReferenceFrame::Local);
    s.contacts.add(s.model, "HL_FOOT", 3, ReferenceFrame::LocalWorldAligned, 0.0, 5.0);
    s.contacts.add(s.model, "HR_FOOT", 3, ReferenceFrame::LocalWorldAligned);
    out.push_back(std::move(s));
  }
  {
    RobotSetup s{"talos_reduced",
                 buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/talos/talos_reduced.urdf",
                                    RootJoint::FreeFlyer),
                 {},
                 "left_sole_link",
                 "gripper_left_base_link"};
    s.contacts.add(s.model, "left_sole_link", 6, ReferenceFrame::LocalWorldAligned, 10.0, 2.0);
    s.contacts.add(s.model, "right_sole_link", 6, ReferenceFrame::Local);
    out.push_back(std::move(s));
  }
  return out;
}

// A knot's data and the context it hands to residuals.
struct Knot {
  static constexpr double kDt = 0.01;
  Knot(const Model& m, const ContactSet& c)
      : model(m), contacts(c), data(m), kd(m, c), q(m.nq), v(m.nv) {}
  const Model& model;
  const ContactSet& contacts;
  Data data;
  KnotData kd;
  Eigen::VectorXd q, v;
  ContactStatus status = ContactStatus::Ok;

  // Contact dynamics with derivatives at (x, u) (λ, Gx, Gu), then forward kinematics of (q, v)
  // and the joint Jacobians: what KnotContext promises.
  KnotContext at(const Eigen::Ref<const Eigen::VectorXd>& x,
                 const Eigen::Ref<const Eigen::VectorXd>& u) {
    q = x.head(model.nq);
    v = x.tail(model.nv);
    status = knotDynamicsDerivatives(model, data, contacts, kd, q, v, u, kDt);
    forwardKinematics(model, data, q, v);
    updateJointJacobians(model, data);
    return KnotContext{model, data, &contacts, &kd.contact.lambda, &kd.Gx, &kd.Gu};
  }
};

inline Eigen::VectorXd randomState(const Model& model, std::mt19937& rng) {
  Eigen::VectorXd x(model.nq + model.nv);
  x.head(model.nq) = randomConfiguration(model, rng);
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  for (int k = 0; k < model.nv; ++k) x[model.nq + k] = d(rng);
  return x;
}

inline Eigen::VectorXd randomUniform(std::mt19937& rng, int n, double scale) {
  std::uniform_real_distribution<double> d(-scale, scale);
  Eigen::VectorXd r(n);
  for (int k = 0; k < n; ++k) r[k] = d(rng);
  return r;
}

struct Term {
  std::string name;
  std::unique_ptr<Residual> residual;
  Activation activation;
};

// One residual of every kind, references drawn near the state x (so that logs stay far from π)
// or at random, each with an activation that exercises its use.
inline std::vector<Term> makeTerms(const RobotSetup& s, int nu, const Eigen::VectorXd& x,
                                   std::mt19937& rng) {
  const Model& m = s.model;
  Data data(m);
  forwardKinematics(m, data, x.head(m.nq));
  const Frame& fa = m.frames[m.getFrameId(s.frame_a)];
  const SE3 oMa = data.oMi[fa.parentJoint] * fa.placement;
  const Vector6d perturb = randomUniform(rng, 6, 0.4);

  std::vector<Term> t;
  const Eigen::VectorXd x_ref = [&] {
    Eigen::VectorXd r(m.nq + m.nv);
    r.head(m.nq) = randomConfiguration(m, rng);
    r.tail(m.nv) = randomUniform(rng, m.nv, 1.0);
    return r;
  }();
  t.push_back({"state", std::make_unique<StateResidual>(m, nu, x_ref),
               Activation::weightedQuadratic(randomUniform(rng, 2 * m.nv, 1.0).cwiseAbs())});
  t.push_back({"control",
               std::make_unique<ControlResidual>(m, nu, randomUniform(rng, nu, 1.0).eval()),
               Activation::quadratic(nu, 0.1)});
  // Half the limit range: random states violate some of them, so the barrier is active.
  t.push_back({"limits", std::make_unique<JointLimitResidual>(m, nu),
               JointLimitResidual::activation(m, 2.0, 0.5)});
  t.push_back({"placement",
               std::make_unique<FramePlacementResidual>(m, nu, s.frame_a, oMa * exp6(perturb)),
               Activation::quadratic(6)});
  t.push_back({"translation",
               std::make_unique<FrameTranslationResidual>(
                   m, nu, s.frame_b, Eigen::Vector3d(randomUniform(rng, 3, 0.5))),
               Activation::smoothAbs(3, 0.05, 3.0)});
  t.push_back({"rotation",
               std::make_unique<FrameRotationResidual>(
                   m, nu, s.frame_a, oMa.R * exp3(randomUniform(rng, 3, 0.4).eval())),
               Activation::quadratic(3, 2.0)});
  t.push_back({"velocity_local",
               std::make_unique<FrameVelocityResidual>(m, nu, s.frame_a, ReferenceFrame::Local,
                                                       Vector6d(randomUniform(rng, 6, 0.5))),
               Activation::quadratic(6)});
  t.push_back(
      {"velocity_lwa",
       std::make_unique<FrameVelocityResidual>(m, nu, s.frame_b, ReferenceFrame::LocalWorldAligned,
                                               Vector6d(randomUniform(rng, 6, 0.5))),
       Activation::quadratic(6, 0.5)});
  t.push_back(
      {"com",
       std::make_unique<ComPositionResidual>(m, nu, Eigen::Vector3d(randomUniform(rng, 3, 0.3))),
       Activation::quadratic(3, 10.0)});
  t.push_back(
      {"momentum",
       std::make_unique<CentroidalMomentumResidual>(m, nu, Vector6d(randomUniform(rng, 6, 1.0))),
       Activation::quadratic(6, 0.1)});
  for (int c = 0; c < 2; ++c) {
    const ContactModel& cm = s.contacts[c];
    t.push_back({"force_" + cm.name,
                 std::make_unique<ContactForceResidual>(m, nu, s.contacts, cm.name,
                                                        randomUniform(rng, cm.dim, 20.0).eval()),
                 Activation::quadratic(cm.dim, 1e-3)});
    t.push_back({"cone_" + cm.name,
                 std::make_unique<FrictionConeResidual>(
                     m, nu, s.contacts, cm.name, 0.6, exp3(randomUniform(rng, 3, 0.3).eval()), 5.0),
                 FrictionConeResidual::activation(1e-2)});
    if (cm.dim == 6)
      t.push_back({"cop_" + cm.name,
                   std::make_unique<CenterOfPressureResidual>(
                       m, nu, s.contacts, cm.name, Eigen::Vector2d(0.1, 0.05),
                       exp3(randomUniform(rng, 3, 0.3).eval())),
                   CenterOfPressureResidual::activation(1e-2)});
  }
  return t;
}

}  // namespace ocp_test
}  // namespace stride
