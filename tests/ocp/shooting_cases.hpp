#pragma once
// The solver's own fixture (tests/ocp/test_solver_no_alloc.cpp, tools/bench fddp_iteration/
// solo12_steps): a shooting problem built from solver/ocp's types alone, as any optimal-control
// user would build one, with nothing of locomotion/ (no contact plan, gait generator or
// locomotion builder), so that the solver's tests and benchmarks do not depend on the planner
// above it. It still has what a locomotion problem gives the solver: knots whose contact sets
// differ, impulse knots, bounds activations (friction cones) and frame terms.
//
// solo12 on its four point feet (forces in world axes), at its SRDF posture lowered so that its
// lowest foot touches z = 0, at rest; 100 knots of 10 ms: all feet down, the FL-HR pair lifted
// 5 cm and put back (an impulse knot at its touch-down), all feet down, the FR-HL pair likewise,
// all feet down to the end. Every knot has the same terms (state, control, a friction cone and a
// foot translation per foot), switched on and off per knot in place, as a receding horizon does:
// the knots share one workspace slot per contact count. Header-only; the robot is read from
// `shared` (the shared data folder).

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "solver/contact/contact_dynamics.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/srdf.hpp"
#include "solver/multibody/urdf.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/problem.hpp"
#include "solver/ocp/residual_contact.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"

namespace stride {
namespace shooting_cases {

constexpr int kKnots = 100;
constexpr double kDt = 0.01;
constexpr double kSwingHeight = 0.05;
constexpr double kMu = 0.6;
constexpr double kMinNormalForce = 1.0;
constexpr double kPi = 3.14159265358979323846;

// The feet, and the pairs that swing: FL-HR lifted on knots [10, 30), landing at 30 (an impulse
// knot); FR-HL lifted on [41, 61), landing at 61.
constexpr const char* kFeet[] = {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"};
struct Swing {
  int lift, land;  // the first knot in the air, the touch-down (impulse) knot
  unsigned feet;   // bit c: foot c swings
};
constexpr Swing kSwings[] = {{10, 30, 0b1001u}, {41, 61, 0b0110u}};

// The running knots' terms, by index in their CostModel (the same on every knot).
constexpr int kStateTerm = 0, kControlTerm = 1;
constexpr int coneTerm(int c) {
  return 2 + 2 * c;
}
constexpr int swingTerm(int c) {
  return 3 + 2 * c;
}

struct Steps {
  Model model;  // first: the problem and the contact sets refer to it
  ContactSet contacts;
  Eigen::VectorXd x0;
  std::unique_ptr<ShootingProblem> problem;
  // The standing warm start: x0 at every knot, each knot's holding torques.
  std::vector<Eigen::VectorXd> xs, us;
};

// The torques that hold posture q still on the contacts of `mask` (bit c: contact c closed):
// g(q) = Sᵀ u + Jcᵀ λ at rest, the base rows fixing λ (minimum norm), the joint rows then u.
inline Eigen::VectorXd holdingTorques(const Model& model, ContactSet contacts,
                                      const Eigen::VectorXd& q, unsigned mask) {
  const int nv = model.nv, nu = actuatedDimension(model), na = nv - nu;
  Data data(model);
  const Eigen::VectorXd g = computeGeneralizedGravity(model, data, q);
  for (int c = 0; c < contacts.size(); ++c) contacts.setActive(c, (mask >> c) & 1u);
  ContactData cd(model, contacts);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(nv);
  Eigen::VectorXd u = g.tail(nu);
  if (contacts.nc() > 0 &&
      contactDynamics(model, data, contacts, cd, q, zero, zero) == ContactStatus::Ok) {
    const Eigen::MatrixXd Jc = cd.Jc.topRows(contacts.nc());
    const Eigen::VectorXd lambda =
        Jc.leftCols(na).transpose().completeOrthogonalDecomposition().solve(g.head(na));
    u -= Jc.rightCols(nu).transpose() * lambda;
  }
  return u;
}

// Which feet are down at knot k (bit c: foot c), and whether k is a touch-down.
inline unsigned closedAt(int k, bool& touchdown) {
  unsigned mask = 0b1111u;
  touchdown = false;
  for (const Swing& s : kSwings) {
    if (k >= s.lift && k < s.land) mask &= ~s.feet;
    touchdown = touchdown || k == s.land;
  }
  return mask;
}

// integrator: of every contact knot (the impulse knots are the same under both).
inline std::unique_ptr<Steps> solo12Steps(const std::string& shared,
                                          Integrator integrator = Integrator::Euler) {
  auto p = std::make_unique<Steps>();
  p->model = buildModelFromUrdf(shared + "/robots/solo12/solo12.urdf", RootJoint::FreeFlyer);
  loadReferenceConfigurations(p->model, shared + "/robots/solo12/solo.srdf");
  const Model& model = p->model;
  for (const char* foot : kFeet) p->contacts.add(model, foot, 3, ReferenceFrame::LocalWorldAligned);
  const int nq = model.nq, nv = model.nv, nu = actuatedDimension(model), nc = p->contacts.size();

  // The standing posture with the lowest foot on the ground, at rest.
  Eigen::VectorXd q = model.referenceConfigurations.at("standing");
  Data data(model);
  framesForwardKinematics(model, data, q);
  double lowest = data.oMf[p->contacts[0].frame].p.z();
  for (int c = 1; c < nc; ++c) lowest = std::min(lowest, data.oMf[p->contacts[c].frame].p.z());
  q[2] -= lowest;
  framesForwardKinematics(model, data, q);
  p->x0 = Eigen::VectorXd::Zero(nq + nv);
  p->x0.head(nq) = q;

  // The weights of the solo12 trot of the locomotion tests (tests/locomotion/locomotion_cases.hpp).
  Eigen::VectorXd w_state(2 * nv);
  w_state.head(nv).setConstant(1.0);
  w_state.tail(nv).setConstant(0.1);
  w_state.head<6>().setConstant(10.0);
  w_state.segment<6>(nv).setConstant(1.0);
  const double w_control = 1e-2, w_swing = 1e5, w_friction = 1e3, w_terminal = 10.0;

  std::vector<Eigen::VectorXd> u_hold(1u << nc);
  for (unsigned mask = 0; mask < u_hold.size(); ++mask)
    u_hold[mask] = holdingTorques(model, p->contacts, q, mask);

  // Two workspaces: the tests and benchmarks run on one thread and on two.
  auto workspace = std::make_shared<SharedWorkspace>(model, 2);
  std::vector<std::unique_ptr<ActionModel>> running;
  p->us.resize(kKnots);
  for (int k = 0; k < kKnots; ++k) {
    auto knot = std::make_unique<KnotModel>(model, p->contacts, kDt, workspace);
    knot->setIntegrator(integrator);
    bool touchdown = false;
    const unsigned mask = closedAt(k, touchdown);
    knot->setMode(touchdown ? KnotMode::Impulse : KnotMode::Contact);
    CostModel& costs = knot->costs();
    costs.add("state", std::make_unique<StateResidual>(model, nu, p->x0),
              Activation::weightedQuadratic(w_state));
    costs.add("control", std::make_unique<ControlResidual>(model, nu, u_hold[mask]),
              Activation::quadratic(nu), w_control);
    for (int c = 0; c < nc; ++c) {
      const bool closed = (mask >> c) & 1u;
      knot->contacts().setActive(c, closed);
      // An impulse knot's cones bound impulses Λ ≈ f dt, weighted as the same force (as the
      // locomotion problem weighs them), with no minimum.
      const int cone = costs.add(
          "cone_" + p->contacts[c].name,
          std::make_unique<FrictionConeResidual>(model, nu, p->contacts, p->contacts[c].name, kMu,
                                                 Eigen::Matrix3d::Identity(),
                                                 touchdown ? 0.0 : kMinNormalForce),
          FrictionConeResidual::activation(), touchdown ? w_friction / (kDt * kDt) : w_friction);
      costs[cone].active = closed;
      // The foot rises and comes down on a half sine while it swings, and lands where it stood.
      Eigen::Vector3d foot = data.oMf[p->contacts[c].frame].p;
      bool swings = false;
      for (const Swing& s : kSwings)
        if ((s.feet >> c) & 1u && k >= s.lift && k <= s.land) {
          swings = true;
          const double phase = static_cast<double>(k - s.lift + 1) / (s.land - s.lift + 1);
          foot.z() += kSwingHeight * std::sin(kPi * phase);
        }
      const int swing =
          costs.add(std::string("swing_") + kFeet[c],
                    std::make_unique<FrameTranslationResidual>(model, nu, kFeet[c], foot),
                    Activation::quadratic(3), w_swing);
      costs[swing].active = swings;
    }
    p->us[k] = u_hold[mask];
    running.push_back(std::move(knot));
  }
  auto terminal = std::make_unique<TerminalModel>(model);
  terminal->costs().add("state", std::make_unique<StateResidual>(model, 0, p->x0),
                        Activation::weightedQuadratic(w_terminal * w_state));
  p->problem = std::make_unique<ShootingProblem>(p->x0, std::move(running), std::move(terminal));
  p->xs.assign(kKnots + 1, p->x0);
  return p;
}

}  // namespace shooting_cases
}  // namespace stride
