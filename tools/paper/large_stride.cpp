#include "tools/paper/large_stride.hpp"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "solver/multibody/frames.hpp"
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
  build(0, plan.N, nullptr, nullptr);
}

StrideProblem::StrideProblem(const Robot& robot, const StridePlan& plan, const StrideDdpOptions& o,
                             int first, int knots, const Eigen::VectorXd& x_terminal,
                             const std::vector<Eigen::VectorXd>* x_refs)
    : robot_(robot), plan_(plan), options_(o) {
  if (first < 0 || first > plan.N || knots < 1)
    throw std::invalid_argument("StrideProblem: window out of range");
  if (x_refs && x_refs->size() != windowKnots(plan, first, knots).size())
    throw std::invalid_argument("StrideProblem: one state reference per knot");
  build(first, knots, &x_terminal, x_refs);
}

std::vector<std::pair<int, bool>> StrideProblem::windowKnots(const StridePlan& plan, int first,
                                                             int knots) {
  std::vector<std::pair<int, bool>> out;
  const int N = plan.N;
  for (int j = 0; j < knots; ++j) {
    const int k = std::min(first + j, N);
    const bool impulse = j > 0 && k > 0 && k != std::min(first + j - 1, N) && plan.touchdown[k];
    if (impulse) out.emplace_back(k, true);
    out.emplace_back(k, false);
  }
  return out;
}

void StrideProblem::build(int first, int knots, const Eigen::VectorXd* x_terminal,
                          const std::vector<Eigen::VectorXd>* x_refs) {
  const Robot& robot = robot_;
  const StridePlan& plan = plan_;
  const StrideDdpOptions& o = options_;
  const Model& model = robot.model;
  const int nq = model.nq, nv = model.nv, nu = nv - 6, N = plan.N;
  ContactSet contacts;
  for (int c = 0; c < 2; ++c)
    contacts.add(model, plan.feet[c], 6, ReferenceFrame::LocalWorldAligned, o.contact_kp,
                 o.contact_kd > 0.0 ? o.contact_kd : 1.0 / plan.options.dt);
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
  for (int j = 0; j < knots; ++j) {
    const int k = std::min(first + j, N);
    const bool impulse = j > 0 && k > 0 && k != std::min(first + j - 1, N) && plan.touchdown[k];
    for (int pass = impulse ? 0 : 1; pass < 2; ++pass) {
      const bool is_impulse = pass == 0;
      auto knot = std::make_unique<KnotModel>(model, contacts, plan.options.dt, workspace);
      knot->setMode(is_impulse ? KnotMode::Impulse : KnotMode::Contact);
      // These knots never change mode: an impulse knot has nothing to integrate, and keeps the
      // lighter Euler workspace.
      if (!is_impulse) knot->setIntegrator(o.integrator);
      for (int c = 0; c < 2; ++c) {
        knot->contacts().setActive(c, plan.closed[k][c]);
        knot->contacts().setReference(c, SE3(Eigen::Matrix3d::Identity(), plan.foot[k][c]));
      }
      CostModel& costs = knot->costs();
      std::vector<int> group;
      costs.add(
          "posture",
          std::make_unique<StateResidual>(model, nu, x_refs ? (*x_refs)[running.size()] : x_ref),
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
  const int k_end = std::min(first + knots, N);
  auto terminal = std::make_unique<TerminalModel>(model);
  terminal->costs().add("posture",
                        std::make_unique<StateResidual>(model, 0, x_terminal ? *x_terminal : x_ref),
                        Activation::weightedQuadratic(o.w_terminal * w_state));
  terminal->costs().add("com", std::make_unique<ComPositionResidual>(model, 0, plan.com[k_end]),
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

}  // namespace stride
