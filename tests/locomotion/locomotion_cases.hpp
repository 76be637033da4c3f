#pragma once
// The locomotion problems of the tests and of the benchmark (tools/bench/bench_ocp.cpp,
// fddp_iteration/<problem>): solo12 standing and trotting, talos_reduced standing and taking one
// step. Each robot stands at its SRDF posture with the base lowered or raised so that its lowest
// foot touches z = 0. Header-only; the robots are read from `shared` (the shared data folder).

#include <algorithm>
#include <functional>
#include <memory>
#include <string>

#include "locomotion/locomotion_problem.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/srdf.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace loco_cases {

// The ground's friction coefficient; the problems plan with kPlanFriction < kGroundFriction. The
// cone is a penalty, whose optimum sits slightly outside the cone it penalizes (and the inscribed
// pyramid's edges touch the circular cone): the margin keeps the forces inside the ground's.
constexpr double kGroundFriction = 0.7;
constexpr double kPlanFriction = 0.6;

struct Robot {
  Model model;
  ContactSet contacts;
  Eigen::VectorXd x_nominal;
};

// The posture `posture` at rest with the lowest contact frame at z = 0.
inline Eigen::VectorXd onTheGround(const Model& model, const ContactSet& contacts,
                                   const std::string& posture) {
  Eigen::VectorXd q = model.referenceConfigurations.at(posture);
  Data data(model);
  framesForwardKinematics(model, data, q);
  double lowest = data.oMf[contacts[0].frame].p.z();
  for (int c = 1; c < contacts.size(); ++c)
    lowest = std::min(lowest, data.oMf[contacts[c].frame].p.z());
  q[2] -= lowest;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(model.nq + model.nv);
  x.head(model.nq) = q;
  return x;
}

// solo12 on four point feet (forces in world axes, so the flat-ground cone is the identity).
inline std::unique_ptr<Robot> solo12(const std::string& shared) {
  auto r = std::make_unique<Robot>();
  r->model = buildModelFromUrdf(shared + "/robots/solo12/solo12.urdf", RootJoint::FreeFlyer);
  loadReferenceConfigurations(r->model, shared + "/robots/solo12/solo.srdf");
  for (const char* foot : {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"})
    r->contacts.add(r->model, foot, 3, ReferenceFrame::LocalWorldAligned);
  r->x_nominal = onTheGround(r->model, r->contacts, "standing");
  return r;
}

// talos_reduced on two 6D soles.
inline std::unique_ptr<Robot> talos(const std::string& shared) {
  auto r = std::make_unique<Robot>();
  r->model = buildModelFromUrdf(shared + "/robots/talos/talos_reduced.urdf", RootJoint::FreeFlyer);
  loadReferenceConfigurations(r->model, shared + "/robots/talos/talos.srdf");
  for (const char* sole : {"left_sole_link", "right_sole_link"})
    r->contacts.add(r->model, sole, 6, ReferenceFrame::LocalWorldAligned);
  r->x_nominal = onTheGround(r->model, r->contacts, "half_sitting");
  return r;
}

inline ContactPlan standing(const Robot& r, double duration) {
  ContactPlan plan;
  ContactPhase all{duration, {}};
  for (int c = 0; c < r.contacts.size(); ++c) all.contacts.push_back(r.contacts[c].name);
  plan.phases.push_back(all);
  return plan;
}

// A trot: double support, then the FL-HR pair swings, double support, the FR-HL pair swings.
inline ContactPlan soloTrot(double support = 0.1, double swing = 0.2) {
  ContactPlan plan;
  plan.cyclic = true;
  plan.phases = {{support, {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"}},
                 {swing, {"FR_FOOT", "HL_FOOT"}},
                 {support, {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"}},
                 {swing, {"FL_FOOT", "HR_FOOT"}}};
  return plan;
}

// Two pronk jumps (issue 45): standing 0.3 s, 0.2 s in the air, 0.3 s down, 0.2 s in the air,
// then down.
inline ContactPlan soloPronk() {
  const std::vector<std::string> all = {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"};
  ContactPlan plan;
  plan.phases = {{0.3, all}, {0.2, {}}, {0.3, all}, {0.2, {}}, {1.0, all}};
  return plan;
}

// One step of the left foot: double support, single support on the right sole, double support.
inline ContactPlan talosStep() {
  ContactPlan plan;
  plan.phases = {{0.3, {"left_sole_link", "right_sole_link"}},
                 {0.5, {"right_sole_link"}},
                 {0.4, {"left_sole_link", "right_sole_link"}}};
  return plan;
}

inline LocomotionOptions soloOptions() {
  LocomotionOptions o;
  o.dt = 0.01;
  o.knots = 100;
  o.mu = kPlanFriction;
  o.min_normal_force = 1.0;
  LocomotionWeights& w = o.weights;
  w.base_position = 10.0;
  w.base_orientation = 10.0;
  w.joint_position = 1.0;
  w.base_velocity = 1.0;
  w.joint_velocity = 0.1;
  w.control = 1e-2;
  w.swing = 1e5;
  w.friction = 1e3;
  w.terminal_state = 10.0;
  return o;
}

inline LocomotionOptions talosOptions() {
  LocomotionOptions o;
  o.dt = 0.02;
  o.knots = 60;
  o.mu = kPlanFriction;
  o.min_normal_force = 20.0;
  LocomotionWeights& w = o.weights;
  w.base_position = 100.0;
  w.base_orientation = 100.0;
  w.joint_position = 10.0;
  w.base_velocity = 1.0;
  w.joint_velocity = 1.0;
  w.control = 1e-3;
  w.swing = 1e6;
  w.friction = 1e1;
  w.terminal_state = 10.0;
  return o;
}

// A problem with the robot it refers to (the problem keeps a reference to the model) and the
// references it is configured from: the plan played by a gait generator, the robot commanded
// forward at `velocity` from its nominal posture.
struct Case {
  std::unique_ptr<Robot> robot;
  std::unique_ptr<LocomotionProblem> loco;
  std::unique_ptr<GaitGenerator> ref;
  BodyCommand velocity;

  // Plans the references from the nominal posture at t0 (as a controller would from a state
  // there) and configures the knots for them.
  bool update(double t0) {
    return ref->plan(t0, robot->x_nominal, t0, t0 + loco->span()) && loco->update(t0, *ref);
  }
  // A warm start on the references: their states and the knots' holding torques.
  void warmStart(std::vector<Eigen::VectorXd>& xs, std::vector<Eigen::VectorXd>& us) const {
    loco->referenceWarmStart(*ref, xs, us);
  }
};

enum class Problem { SoloStand, SoloTrot, SoloPronk, TalosStand, TalosStep };
inline const char* name(Problem p) {
  switch (p) {
    case Problem::SoloStand:
      return "solo12_stand";
    case Problem::SoloTrot:
      return "solo12_trot";
    case Problem::SoloPronk:
      return "solo12_pronk";
    case Problem::TalosStand:
      return "talos_stand";
    case Problem::TalosStep:
      return "talos_walk";
  }
  return "?";
}

// adjust: changes to the options before building (e.g. impulses off).
inline Case make(Problem p, const std::string& shared,
                 const std::function<void(LocomotionOptions&)>& adjust = {}) {
  Case c;
  const bool solo = p == Problem::SoloStand || p == Problem::SoloTrot || p == Problem::SoloPronk;
  c.robot = solo ? solo12(shared) : talos(shared);
  LocomotionOptions o = solo ? soloOptions() : talosOptions();
  ContactPlan plan;
  switch (p) {
    case Problem::SoloStand:
      plan = standing(*c.robot, 1.0);
      break;
    case Problem::SoloTrot:
      plan = soloTrot();
      break;
    case Problem::SoloPronk:
      plan = soloPronk();
      break;
    case Problem::TalosStand:
      o.knots = 50;
      plan = standing(*c.robot, 1.0);
      break;
    case Problem::TalosStep:
      plan = talosStep();
      break;
  }
  if (adjust) adjust(o);
  c.loco =
      std::make_unique<LocomotionProblem>(c.robot->model, c.robot->contacts, c.robot->x_nominal, o);
  GaitGeneratorOptions g;
  g.swing_height = 0.05;
  g.horizon = c.loco->span();
  g.sample_dt = o.dt;
  c.ref = std::make_unique<GaitGenerator>(c.robot->model, c.robot->contacts, c.robot->x_nominal, g);
  c.ref->timeline().reset(c.ref->timeline().addPattern(plan), 0.0);
  // The trot steps 5 cm per touch-down (a foot lands every 0.6 s); talos's step is 10 cm.
  if (p == Problem::SoloTrot) c.velocity.vx = 0.05 / 0.6;
  if (p == Problem::TalosStep) c.velocity.vx = 0.1 / 1.2;
  c.ref->setCommand(c.velocity);
  c.update(0.0);
  return c;
}

}  // namespace loco_cases
}  // namespace stride
