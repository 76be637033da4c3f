#include "tools/paper/large_stride.hpp"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "sim/policy.hpp"
#include "sim/simulator.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/residual_com.hpp"
#include "solver/ocp/residual_contact.hpp"
#include "solver/ocp/residual_cop.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"

namespace stride {

namespace {
enum Group { kCom = 0, kFeet, kForces, kTorque, kPosture, kContact, kGroups };
}  // namespace

const std::vector<std::string>& strideCostGroups() {
  static const std::vector<std::string> names = {"com",    "feet",    "forces",
                                                 "torque", "posture", "contact"};
  return names;
}

StrideProblem::StrideProblem(const Robot& robot, const StridePlan& plan, const StrideDdpOptions& o)
    : robot_(robot), plan_(plan), options_(o) {
  const Model& model = robot.model;
  const int nq = model.nq, nv = model.nv, nu = nv - 6, N = plan.N;
  ContactSet contacts;
  for (int c = 0; c < 2; ++c)
    contacts.add(model, plan.feet[c], 6, ReferenceFrame::LocalWorldAligned, 0.0, o.contact_kd);
  // State weights: base position free (the CoM term places the body), base orientation upright,
  // joints to the nominal posture, velocities to zero.
  Eigen::VectorXd w_state(2 * nv);
  w_state.head(nv).setConstant(o.w_posture);
  w_state.head<3>().setZero();
  w_state.segment<3>(3).setConstant(o.w_base_orientation);
  w_state.tail(nv).setConstant(o.w_velocity);
  Eigen::VectorXd x_ref(nq + nv);
  x_ref << robot.default_q, Eigen::VectorXd::Zero(nv);
  const Eigen::Vector2d sole = o.sole_margin * robot.sole_half_extents;

  auto workspace = std::make_shared<SharedWorkspace>(model, std::max(omp_get_max_threads(), 2));
  std::vector<std::unique_ptr<ActionModel>> running;
  for (int k = 0; k < N; ++k) {
    const bool impulse = k > 0 && plan.touchdown[k];
    for (int pass = impulse ? 0 : 1; pass < 2; ++pass) {
      const bool is_impulse = pass == 0;
      auto knot = std::make_unique<KnotModel>(model, contacts, plan.options.dt, workspace);
      knot->setMode(is_impulse ? KnotMode::Impulse : KnotMode::Contact);
      for (int c = 0; c < 2; ++c) knot->contacts().setActive(c, plan.closed[k][c]);
      CostModel& costs = knot->costs();
      std::vector<int> group;
      costs.add("posture", std::make_unique<StateResidual>(model, nu, x_ref),
                Activation::weightedQuadratic(w_state));
      group.push_back(kPosture);
      costs.add("torque", std::make_unique<ControlResidual>(model, nu), Activation::quadratic(nu),
                o.w_torque);
      group.push_back(kTorque);
      if (!is_impulse) {
        costs.add("com", std::make_unique<ComPositionResidual>(model, nu, plan.com[k]),
                  Activation::quadratic(3), o.w_com);
        group.push_back(kCom);
      }
      for (int c = 0; c < 2; ++c) {
        const std::string& name = plan.feet[c];
        costs.add("foot_" + name,
                  std::make_unique<FramePlacementResidual>(
                      model, nu, name, SE3(Eigen::Matrix3d::Identity(), plan.foot[k][c])),
                  Activation::quadratic(6), o.w_foot);
        group.push_back(kFeet);
        if (is_impulse || !plan.closed[k][c]) continue;
        costs.add("force_" + name,
                  std::make_unique<ContactForceResidual>(model, nu, contacts, name,
                                                         Eigen::VectorXd(plan.force[k][c])),
                  Activation::quadratic(6), o.w_force);
        group.push_back(kForces);
        costs.add("cone_" + name,
                  std::make_unique<FrictionConeResidual>(model, nu, contacts, name, o.mu),
                  FrictionConeResidual::activation(), o.w_cone);
        group.push_back(kContact);
        costs.add("cop_" + name,
                  std::make_unique<CenterOfPressureResidual>(model, nu, contacts, name, sole),
                  CenterOfPressureResidual::activation(), o.w_cop);
        group.push_back(kContact);
      }
      sample_.push_back(k);
      impulse_.push_back(is_impulse ? 1 : 0);
      if (!is_impulse) contact_knot_.push_back(static_cast<int>(running.size()));
      term_group_.push_back(group);
      term_active_.push_back(std::vector<char>(group.size(), 1));
      running.push_back(std::move(knot));
    }
  }
  auto terminal = std::make_unique<TerminalModel>(model);
  terminal->costs().add("posture", std::make_unique<StateResidual>(model, 0, x_ref),
                        Activation::weightedQuadratic(o.w_terminal * w_state));
  terminal->costs().add("com", std::make_unique<ComPositionResidual>(model, 0, plan.com[N]),
                        Activation::quadratic(3), o.w_com);
  term_group_.push_back({kPosture, kCom});
  term_active_.push_back({1, 1});
  Eigen::VectorXd x0(nq + nv);
  x0 << robot.default_q, Eigen::VectorXd::Zero(nv);
  problem_ = std::make_unique<ShootingProblem>(x0, std::move(running), std::move(terminal));
  const double inf = std::numeric_limits<double>::infinity();
  u_lower_ = Eigen::VectorXd::Constant(nu, -inf);
  u_upper_ = Eigen::VectorXd::Constant(nu, inf);
  if (o.torque_limits) {
    u_upper_ = model.effortLimit.tail(nu);
    u_lower_ = -u_upper_;
  }
}

void StrideProblem::warmStart(const IkTrajectory& ik, std::vector<Eigen::VectorXd>& xs,
                              std::vector<Eigen::VectorXd>& us) {
  const int T = problem_->horizon(), nq = model().nq, nv = model().nv;
  auto state = [&](int k) {
    Eigen::VectorXd x(nq + nv);
    x << ik.q[k], ik.v[k];
    return x;
  };
  xs.resize(T + 1);
  us.resize(T);
  for (int j = 0; j < T; ++j) {
    xs[j] = state(sample_[j]);
    us[j] = ik.tau[sample_[j]];
  }
  xs[T] = state(plan_.N);
  problem_->setX0(xs[0]);
}

void StrideProblem::setGroup(int group) {
  const int T = problem_->horizon();
  for (int j = 0; j <= T; ++j) {
    CostModel& costs = j < T ? static_cast<KnotModel&>(problem_->knot(j)).costs()
                             : static_cast<TerminalModel&>(problem_->terminal()).costs();
    for (int i = 0; i < costs.size(); ++i)
      costs[i].active = term_active_[j][i] && (group < 0 || term_group_[j][i] == group);
  }
}

std::vector<double> StrideProblem::costBreakdown(const std::vector<Eigen::VectorXd>& xs,
                                                 const std::vector<Eigen::VectorXd>& us) {
  std::vector<double> out(kGroups, 0.0);
  for (int g = 0; g < kGroups; ++g) {
    setGroup(g);
    out[g] = problem_->calc(xs, us);
  }
  setGroup(-1);
  problem_->calc(xs, us);
  return out;
}

std::vector<std::array<Vector6d, 2>> StrideProblem::forces(const std::vector<Eigen::VectorXd>& xs,
                                                           const std::vector<Eigen::VectorXd>& us) {
  problem_->calc(xs, us);
  std::vector<std::array<Vector6d, 2>> out(plan_.N, {Vector6d::Zero(), Vector6d::Zero()});
  for (int k = 0; k < plan_.N; ++k) {
    const auto& d = static_cast<const KnotActionData&>(problem_->data(contact_knot_[k]));
    int row = 0;
    for (int c = 0; c < 2; ++c) {
      if (!plan_.closed[k][c]) continue;
      out[k][c] = d.forces().segment<6>(row);
      row += 6;
    }
  }
  return out;
}

StrideMetrics strideMetrics(const Model& model, const StridePlan& plan,
                            const std::vector<Eigen::VectorXd>& tau,
                            const std::vector<std::array<Vector6d, 2>>& force) {
  StrideMetrics m;
  const int nu = model.nv - 6;
  const int knee[2] = {model.joints[model.getJointId("L_knee")].idx_v - 6,
                       model.joints[model.getJointId("R_knee")].idx_v - 6};
  for (int k = 0; k < plan.N; ++k) {
    for (int c = 0; c < 2; ++c) {
      m.peak_normal_force[c] = std::max(m.peak_normal_force[c], force[k][c][2]);
      m.peak_knee_torque_Nm = std::max(m.peak_knee_torque_Nm, std::abs(tau[k][knee[c]]));
    }
    m.peak_total_normal_force_N =
        std::max(m.peak_total_normal_force_N, force[k][0][2] + force[k][1][2]);
    m.torque_cost += plan.options.dt * tau[k].head(nu).squaredNorm();
  }
  m.peak_normal_force_N = std::max(m.peak_normal_force[0], m.peak_normal_force[1]);
  return m;
}

StrideSolve solveStrides(StrideProblem& sp, const IkTrajectory& ik, int iterations, bool verbose) {
  StrideSolve out;
  std::vector<Eigen::VectorXd> xs, us;
  sp.warmStart(ik, xs, us);
  Solver solver(sp.problem(), SolverKind::BoxFddp);
  solver.setControlBounds(sp.controlLower(), sp.controlUpper());
  if (verbose) solver.callback = Solver::printIterationTable;
  out.breakdown.push_back(sp.costBreakdown(xs, us));
  out.cost.push_back(sp.problem().calc(xs, us));
  out.gap.push_back(0.0);
  solver.setWarmStart(xs, us);
  const auto t0 = std::chrono::steady_clock::now();
  double solve_time = 0.0;
  SolveStatus status = SolveStatus::MaxIterations;
  for (int it = 0; it < iterations; ++it) {
    const auto a = std::chrono::steady_clock::now();
    status = solver.solve(1);
    solve_time += std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
    if (solver.iterations() == 0) break;
    ++out.iterations;
    out.breakdown.push_back(sp.costBreakdown(solver.xs(), solver.us()));
    out.cost.push_back(solver.cost());
    out.gap.push_back(solver.gap());
    if (status != SolveStatus::MaxIterations) break;
  }
  (void)t0;
  out.solve_time_s = solve_time;
  out.status = toString(status);
  out.xs = solver.xs();
  out.us = solver.us();
  out.K = solver.K();
  return out;
}

StrideSimResult simulateStrides(const Robot& robot, StrideProblem& sp, const StrideSolve& solve,
                                double hold_s) {
  const Model& model = robot.model;
  const StridePlan& plan = sp.plan();
  const int nq = model.nq, nv = model.nv, nu = nv - 6, N = plan.N;
  const double dt = plan.options.dt;
  sim::Policy policy;
  policy.resize(N, nq, nv, nu);
  policy.t0 = 0.0;
  policy.dt = dt;
  for (int k = 0; k < N; ++k) {
    const int j = sp.contactKnot(k);
    std::copy(solve.xs[j].data(), solve.xs[j].data() + nq + nv, policy.xRef(k));
    std::copy(solve.us[j].data(), solve.us[j].data() + nu, policy.uFf(k));
    // The solver's law u = us + K (x ⊖ xs); the policy's u_ff + K' (x_ref ⊖ x): K' = -K.
    double* out = policy.gain(k);
    for (int r = 0; r < nu; ++r)
      for (int c = 0; c < 2 * nv; ++c) out[r * 2 * nv + c] = -solve.K[j](r, c);
  }
  StrideSimResult res;
  sim::SimOptions so;
  sim::Simulator simulator(robot, so);
  simulator.reset(solve.xs[0].head(nq), solve.xs[0].tail(nv));
  sim::PolicyEvaluator evaluator(model, nu);
  Eigen::VectorXd tau(nu);
  const int steps_per_knot = static_cast<int>(std::lround(dt / so.dt));
  const int total = static_cast<int>(std::lround((N * dt + hold_s) / so.dt));
  std::array<double, 2> acc{0.0, 0.0};
  const Eigen::VectorXd q_end = solve.xs.back().head(nq);
  for (int s = 0; s < total; ++s) {
    const double t = simulator.time();
    evaluator.evaluate(policy, t, simulator.q(), simulator.v(), tau);
    simulator.step(tau);
    for (int c = 0; c < 2; ++c) {
      const double f = simulator.normalForce(c);
      res.peak_normal_force[c] = std::max(res.peak_normal_force[c], f);
      acc[c] += f / steps_per_knot;
    }
    const Eigen::VectorXd& q = simulator.q();
    const double qx = q[3], qy = q[4];
    const double tilt =
        std::acos(std::clamp(1.0 - 2.0 * (qx * qx + qy * qy), -1.0, 1.0)) * 180.0 / M_PI;
    res.max_tilt_deg = std::max(res.max_tilt_deg, tilt);
    const int k = std::min(static_cast<int>(simulator.time() / dt + 1e-9), N);
    const Eigen::Vector3d base_ref =
        k < N ? Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(policy.xRef(k)))
              : Eigen::Vector3d(q_end.head<3>());
    const double err = (q.head<3>() - base_ref).norm();
    res.max_base_error = std::max(res.max_base_error, err);
    if ((s + 1) % steps_per_knot == 0) {
      for (int c = 0; c < 2; ++c)
        res.peak_normal_force_knot[c] = std::max(res.peak_normal_force_knot[c], acc[c]);
      res.trace.push_back({simulator.time(), acc[0], acc[1], q[0], q[2]});
      acc = {0.0, 0.0};
    }
    if (!res.fell && (tilt > 45.0 || q[2] < 0.5 * q_end[2])) {
      res.fell = true;
      res.fall_time = simulator.time();
      break;
    }
  }
  res.clamped_steps = static_cast<int>(simulator.counters().clamped_steps);
  res.final_base_error = (simulator.q().head<3>() - q_end.head<3>()).norm();
  const bool feet_down = simulator.normalForce(0) > 0.0 && simulator.normalForce(1) > 0.0;
  res.completed = !res.fell && feet_down && res.final_base_error < 0.1;
  return res;
}

}  // namespace stride
