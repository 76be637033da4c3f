#include "tools/paper/astronaut.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/residual_com.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"

namespace stride {

namespace {
Eigen::Matrix3d rotY(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
}

// Posture weights on x ⊖ x_ref: the base is free (its pose is the task, its velocity follows
// from the momentum), the joints are pulled towards the default posture.
Eigen::VectorXd postureWeights(const Model& model, double w_q, double w_v) {
  Eigen::VectorXd w = Eigen::VectorXd::Zero(2 * model.nv);
  w.segment(6, model.nv - 6).setConstant(w_q);
  w.tail(model.nv - 6).setConstant(w_v);
  return w;
}
// Left/right mirror symmetry of the legs: r = [q_a - q_b; v_a - v_b; u_a - u_b] for joint pairs
// (a, b) (1-dof joints). The robot is mirror symmetric about its sagittal plane, and so are the
// start, the goals Ry(θ) and every other cost, so a mirror-symmetric motion keeps the whole-body
// angular momentum's roll and yaw parts zero by symmetry: each leg's r × p about x and z is the
// negative of the other's. Without this term the solver breaks the symmetry (see README: the
// legs move one at a time and the base rolls and yaws by ~20°). Linear in (x, u): its Jacobian
// rows are e_a - e_b, so addGaussNewton adds them directly.
class MirrorResidual : public Residual {
 public:
  MirrorResidual(const Model& model, int nu,
                 const std::vector<std::pair<std::string, std::string>>& pairs)
      : Residual(3 * static_cast<int>(pairs.size()), model.nv, nu, Dependence::StateControl),
        np_(static_cast<int>(pairs.size())),
        nq_(model.nq),
        nj_(model.nv - nu) {
    for (const auto& [a, b] : pairs) {
      const auto& ja = model.joints[model.getJointId(a)];
      const auto& jb = model.joints[model.getJointId(b)];
      if (ja.nv != 1 || jb.nv != 1 || ja.nq != 1 || jb.nq != 1)
        throw std::invalid_argument("MirrorResidual: '" + a + "', '" + b + "' must be 1-dof");
      q_.emplace_back(ja.idx_q, jb.idx_q);
      v_.emplace_back(ja.idx_v, jb.idx_v);
    }
  }

  void calc(ResidualData& d, const KnotContext&, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override {
    for (int i = 0; i < np_; ++i) {
      d.r[i] = x[q_[i].first] - x[q_[i].second];
      d.r[np_ + i] = x[nq_ + v_[i].first] - x[nq_ + v_[i].second];
      // The torques act on the joints after the base's (nv - nu) velocity entries.
      d.r[2 * np_ + i] = u.size() ? u[v_[i].first - nj_] - u[v_[i].second - nj_] : 0.0;
    }
  }
  void calcDiff(ResidualData& d, const KnotContext&, const Eigen::Ref<const Eigen::VectorXd>&,
                const Eigen::Ref<const Eigen::VectorXd>&) const override {
    // Rewritten every time: the knots share the workspace between residuals of one type (knot.hpp).
    d.Rx.setZero();
    d.Ru.setZero();
    const int nv = this->nv();
    for (int i = 0; i < np_; ++i) {
      const auto [a, b] = v_[i];
      d.Rx(i, a) = 1.0;
      d.Rx(i, b) = -1.0;
      d.Rx(np_ + i, nv + a) = 1.0;
      d.Rx(np_ + i, nv + b) = -1.0;
      if (nu() > 0) {
        d.Ru(2 * np_ + i, a - nj_) = 1.0;
        d.Ru(2 * np_ + i, b - nj_) = -1.0;
      }
    }
  }
  void addGaussNewton(const ResidualData&, const Eigen::Ref<const Eigen::VectorXd>& g,
                      const Eigen::Ref<const Eigen::VectorXd>& h,
                      CostDerivatives& out) const override {
    // Row i is e_a - e_b: gradient g_i (e_a - e_b), Hessian h_i (e_a - e_b)(e_a - e_b)ᵀ.
    auto add = [&](auto& L, auto& H, int a, int b, double gi, double hi) {
      L[a] += gi;
      L[b] -= gi;
      H(a, a) += hi;
      H(b, b) += hi;
      H(a, b) -= hi;
      H(b, a) -= hi;
    };
    const int nv = this->nv();
    for (int i = 0; i < np_; ++i) {
      const auto [a, b] = v_[i];
      add(out.Lx, out.Lxx, a, b, g[i], h[i]);
      add(out.Lx, out.Lxx, nv + a, nv + b, g[np_ + i], h[np_ + i]);
      if (nu() > 0) add(out.Lu, out.Luu, a - nj_, b - nj_, g[2 * np_ + i], h[2 * np_ + i]);
    }
  }

 private:
  int np_, nq_, nj_;
  std::vector<std::pair<int, int>> q_, v_;
};

// Weights of the mirror residual's rows: positions, rates, torques.
Eigen::VectorXd mirrorWeights(int pairs, double w_q, double w_v, double w_u) {
  Eigen::VectorXd w(3 * pairs);
  w << Eigen::VectorXd::Constant(pairs, w_q), Eigen::VectorXd::Constant(pairs, w_v),
      Eigen::VectorXd::Constant(pairs, w_u);
  return w;
}
}  // namespace

AstronautProblem::AstronautProblem(const Robot& robot, const AstronautOptions& options, int first,
                                   int last, const Eigen::VectorXd& start,
                                   const std::vector<double>& goals)
    : options_(options), locked_(lockJoints(robot, options.free_joints)) {
  Model& model = locked_.model;
  // Floating in space (§V-B): no gravity; an empty contact set gives the free-floating dynamics.
  model.gravity.setZero();
  const int nv = model.nv, nu = nv - 6;
  x0_ = Eigen::VectorXd::Zero(model.nq + nv);
  x0_.head(model.nq) = locked_.default_q;
  x0_.head(3).setZero();

  // Waypoint i at knot round(i T / n) asks for Ry(i·turn/n).
  const double turn = options.turn_deg * M_PI / 180.0;
  for (int i = 1; i <= options.waypoints; ++i)
    waypoints_.emplace_back(
        static_cast<int>(std::lround(double(i) * options.knots / options.waypoints)),
        turn * i / options.waypoints);
  const int n = static_cast<int>(waypoints_.size());
  if (last < 0 || last > n) last = n;
  if (first < 0 || first >= last)
    throw std::invalid_argument("AstronautProblem: need 0 <= first < last <= waypoints");
  const bool at_end = last == n;
  // Goal angle at waypoint i (0 at the start of the motion).
  auto goal = [&](int i) {
    if (goals.size() == static_cast<std::size_t>(last - first + 1)) return goals[i - first];
    return i == 0 ? 0.0 : waypoints_[i - 1].second;
  };
  const int k0 = waypointKnot(first), T = waypointKnot(last) - k0;
  // Is global knot k within the width of an intermediate waypoint of the window? (its index)
  auto waypointAt = [&](int k) {
    for (int i = first + 1; i < last; ++i)
      if (std::abs(k - waypointKnot(i)) <= options.waypoint_width) return i;
    return 0;
  };

  const bool mirrored =
      !options.mirror.empty() &&
      (options.w_mirror > 0.0 || options.w_mirror_velocity > 0.0 || options.w_mirror_control > 0.0);
  const ContactSet none;
  auto workspace = std::make_shared<SharedWorkspace>(model, std::max(omp_get_max_threads(), 2));
  std::vector<std::unique_ptr<ActionModel>> running;
  for (int k = 0; k < T; ++k) {
    auto knot = std::make_unique<KnotModel>(model, none, options.dt, workspace);
    knot->setIntegrator(options.integrator);
    CostModel& costs = knot->costs();
    const int wp = waypointAt(k0 + k);
    costs.add("posture", std::make_unique<StateResidual>(model, nu, x0_),
              Activation::weightedQuadratic(
                  postureWeights(model, options.w_posture, options.w_joint_velocity)));
    costs.add("control", std::make_unique<ControlResidual>(model, nu), Activation::quadratic(nu),
              options.w_control);
    costs.add("momentum", std::make_unique<CentroidalMomentumResidual>(model, nu),
              Activation::quadratic(6), options.w_momentum);
    costs.add("limits", std::make_unique<JointLimitResidual>(model, nu),
              JointLimitResidual::activation(model, 1.0, options.limit_margin), options.w_limits);
    if (mirrored)
      costs.add("mirror", std::make_unique<MirrorResidual>(model, nu, options.mirror),
                Activation::weightedQuadratic(
                    mirrorWeights(static_cast<int>(options.mirror.size()), options.w_mirror,
                                  options.w_mirror_velocity, options.w_mirror_control)));
    // Every knot carries the orientation term (one workspace slot for all); it is on only near
    // the waypoints before the terminal one.
    const int term = costs.add("orientation",
                               std::make_unique<FrameRotationResidual>(
                                   model, nu, options.base_frame, Eigen::Matrix3d::Identity()),
                               Activation::quadratic(3), options.w_orientation);
    costs[term].active = wp > 0;
    if (wp > 0) costs.residual<FrameRotationResidual>("orientation")->setReference(rotY(goal(wp)));
    running.push_back(std::move(knot));
  }
  // The last waypoint ends the motion at rest; a window ending earlier only reaches its goal.
  auto terminal = std::make_unique<TerminalModel>(model);
  Eigen::VectorXd wT = postureWeights(
      model, options.w_posture, at_end ? options.w_terminal_velocity : options.w_joint_velocity);
  if (at_end) wT.segment(nv + 3, 3).setConstant(options.w_terminal_velocity);  // base ang. velocity
  terminal->costs().add("posture", std::make_unique<StateResidual>(model, 0, x0_),
                        Activation::weightedQuadratic(wT));
  terminal->costs().add("limits", std::make_unique<JointLimitResidual>(model, 0),
                        JointLimitResidual::activation(model, 1.0, options.limit_margin),
                        options.w_limits);
  if (mirrored)
    terminal->costs().add("mirror", std::make_unique<MirrorResidual>(model, 0, options.mirror),
                          Activation::weightedQuadratic(
                              mirrorWeights(static_cast<int>(options.mirror.size()),
                                            options.w_mirror, options.w_mirror_velocity, 0.0)));
  terminal->costs().add(
      "orientation",
      std::make_unique<FrameRotationResidual>(model, 0, options.base_frame, rotY(goal(last))),
      Activation::quadratic(3), options.w_orientation);
  problem_ = std::make_unique<ShootingProblem>(start.size() ? start : x0_, std::move(running),
                                               std::move(terminal));
  problem_->setThreads(workspace->threads());
}

AstronautSolution solveAstronaut(const Robot& robot, const AstronautOptions& options,
                                 const std::function<void(const AstronautWindow&)>& progress,
                                 const std::function<void(const IterationStats&)>& callback) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  AstronautSolution s;
  s.problem = std::make_unique<AstronautProblem>(robot, options);
  const AstronautProblem& full = *s.problem;
  const int n = static_cast<int>(full.waypoints().size());
  const int width = options.window < 1 ? n : options.window;
  s.xs.push_back(full.x0());
  double pitch = 0.0;
  const double step =
      (options.window_step_deg > 0.0 ? options.window_step_deg : options.turn_deg / n) * M_PI /
      180.0;
  // The warm start of the next window: what the last one planned beyond its committed part, then
  // zero torques. The first window starts from zero torques (paper). Ddp rolls the torques out
  // from the window's start, so the states only matter for Fddp.
  std::vector<Eigen::VectorXd> xs, us;
  for (int first = 0; first < n;) {
    const int last = std::min(first + width, n);
    // The window's goals: `step` per segment from the orientation reached so far, never past the
    // final goal. A motion behind schedule is then never asked for more than the window's steps
    // (catching up with a fixed schedule would bring the goals past 180° ahead again, where they
    // pull backwards), and one ahead of it is not pulled back.
    std::vector<double> goals;
    for (int i = first; i <= last; ++i)
      goals.push_back(std::min(pitch + (i - first) * step, full.waypoints().back().second));
    goals.front() = pitch;
    AstronautProblem window(robot, options, first, last, s.xs.back(), goals);
    const int T = window.horizon(), nu = window.model().nv - 6;
    us.resize(static_cast<std::size_t>(T), Eigen::VectorXd::Zero(nu));
    xs.resize(static_cast<std::size_t>(T) + 1, xs.empty() ? s.xs.back() : xs.back());
    xs.front() = s.xs.back();
    Solver solver(window.problem(), options.solver);
    if (callback) solver.callback = callback;
    const int budget = last == n ? options.final_iterations : options.window_iterations;
    solver.setWarmStart(xs, us);
    const auto t0 = Clock::now();
    SolveStatus status = solver.solve(budget);
    const bool restarted = status == SolveStatus::NonFinite;
    if (restarted) {
      // The shifted torques can blow up from the new start (the floating chain is unstable open
      // loop): the window again from zero torques.
      std::fill(us.begin(), us.end(), Eigen::VectorXd::Zero(nu));
      std::fill(xs.begin(), xs.end(), s.xs.back());
      solver.setWarmStart(xs, us);
      status = solver.solve(budget);
    }
    if (status == SolveStatus::NonFinite) {  // nothing to commit: the plan stops here
      s.finite = false;
      break;
    }
    AstronautWindow w;
    w.solve_s = std::chrono::duration<double>(Clock::now() - t0).count();
    w.first = first;
    w.last = last;
    w.committed = last == n ? last - first : std::clamp(options.window_commit, 1, last - first);
    w.knots = T;
    w.goal = goals[w.committed];
    w.iterations = solver.iterations();
    w.status = status;
    w.restarted = restarted;
    // Commit: the states after the window's start and their torques.
    const int kc = full.waypointKnot(first + w.committed) - full.waypointKnot(first);
    const std::vector<Eigen::VectorXd> piece(solver.xs().begin(), solver.xs().begin() + kc + 1);
    pitch += analyzeMotion(window.model(), piece, options.dt, options.base_frame).pitch_axis.back();
    w.pitch = pitch;
    s.xs.insert(s.xs.end(), solver.xs().begin() + 1, solver.xs().begin() + kc + 1);
    s.us.insert(s.us.end(), solver.us().begin(), solver.us().begin() + kc);
    xs.assign(solver.xs().begin() + kc, solver.xs().end());
    us.assign(solver.us().begin() + kc, solver.us().end());
    for (int i = 0; i < solver.statsCount(); ++i) {
      s.stats.push_back(solver.stats()[i]);
      s.stats_window.push_back(static_cast<int>(s.windows.size()));
    }
    s.iterations += w.iterations;
    s.solve_s += w.solve_s;
    s.windows.push_back(w);
    if (progress) progress(w);
    first += w.committed;
  }
  if (s.finite) s.cost = s.problem->problem().calc(s.xs, s.us);
  s.wall_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  return s;
}

AstronautMotion analyzeMotion(const Model& model, const std::vector<Eigen::VectorXd>& xs, double dt,
                              const std::string& base_frame) {
  AstronautMotion m;
  Data data(model);
  const int base = model.getFrameId(base_frame);
  // The legs: the bodies each hip_pitch joint moves (its subtree). The hip yaw / roll links are
  // locked, so they are part of the base body and not counted.
  auto subtree = [&](const std::string& root) {
    std::vector<int> joints;
    if (!model.existJoint(root)) return joints;
    const int r = model.getJointId(root);
    for (int i = 1; i < model.njoints(); ++i)
      for (int j = i; j > 0; j = model.joints[j].parent)
        if (j == r) {
          joints.push_back(i);
          break;
        }
    return joints;
  };
  const std::vector<int> left = subtree("L_hip_pitch"), right = subtree("R_hip_pitch");
  auto legMomentum = [&](const std::vector<int>& joints, const Eigen::Vector3d& c) {
    Eigen::Vector3d h = Eigen::Vector3d::Zero();
    for (int i : joints) {
      // Body momentum in its joint frame, to world axes about the world origin, then about c.
      const Vector6d f = data.oMi[i].actForce(model.inertias[i] * data.v[i]);
      h += f.tail<3>() - c.cross(f.head<3>());
    }
    return h;
  };

  Eigen::Matrix3d R_prev = Eigen::Matrix3d::Identity();
  double pitch = 0.0, off = 0.0, axis = 0.0, axis_prev = 0.0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const Eigen::VectorXd q = xs[k].head(model.nq), v = xs[k].tail(model.nv);
    const Vector6d hg = computeCentroidalMomentum(model, data, q, v);  // also forward kinematics
    const Eigen::Matrix3d R = updateFramePlacement(model, data, base).R;
    if (k > 0) {
      const Eigen::Vector3d w = log3(R * R_prev.transpose());  // world axes
      pitch += w.y();
      off += std::hypot(w.x(), w.z());
    }
    // Forward axis R e_x = (cos θ, ·, -sin θ) for R = Ry(θ); the step wrapped to (-π, π].
    const double a = std::atan2(-R(2, 0), R(0, 0));
    if (k > 0) axis += std::remainder(a - axis_prev, 2.0 * M_PI);
    axis_prev = a;
    R_prev = R;
    m.t.push_back(dt * static_cast<double>(k));
    m.pitch.push_back(pitch);
    m.pitch_axis.push_back(axis);
    m.off_axis.push_back(off);
    m.tilt.push_back(std::acos(std::clamp(R(1, 1), -1.0, 1.0)));
    m.max_tilt = std::max(m.max_tilt, m.tilt.back());
    // R = Ry(θ) Rz(ψ) Rx(φ): row 1 of R is (sin ψ, cos ψ cos φ, -cos ψ sin φ).
    m.yaw.push_back(std::asin(std::clamp(R(1, 0), -1.0, 1.0)));
    m.roll.push_back(std::atan2(-R(1, 2), R(1, 1)));
    m.max_yaw = std::max(m.max_yaw, std::abs(m.yaw.back()));
    m.max_roll = std::max(m.max_roll, std::abs(m.roll.back()));
    m.h.push_back(hg.tail<3>());
    m.com.push_back(data.com);
    m.h_left.push_back(legMomentum(left, data.com));
    m.h_right.push_back(legMomentum(right, data.com));
    m.max_h = std::max(m.max_h, m.h.back().norm());
    m.max_h_leg = std::max({m.max_h_leg, m.h_left.back().norm(), m.h_right.back().norm()});
    m.max_com_drift = std::max(m.max_com_drift, (data.com - m.com.front()).norm());
  }
  return m;
}

FineCheck checkWithFinerSteps(const Model& model, const std::vector<Eigen::VectorXd>& xs,
                              const std::vector<Eigen::VectorXd>& us, double dt, int substeps,
                              const std::string& base_frame, Integrator integrator) {
  KnotModel knot(model, ContactSet(), dt / substeps);
  knot.setIntegrator(integrator);
  auto kd = knot.createData();
  Data data(model);
  const int base = model.getFrameId(base_frame);
  auto momentum = [&](const Eigen::VectorXd& x) {
    return Eigen::Vector3d(
        computeCentroidalMomentum(model, data, x.head(model.nq), x.tail(model.nv)).tail<3>());
  };
  auto rotation = [&](const Eigen::VectorXd& x) {
    forwardKinematics(model, data, x.head(model.nq));
    return Eigen::Matrix3d(updateFramePlacement(model, data, base).R);
  };
  FineCheck c;
  for (std::size_t k = 0; k < us.size(); ++k) {
    Eigen::VectorXd x = xs[k];
    for (int s = 0; s < substeps; ++s) {
      knot.calc(*kd, x, us[k]);
      x = kd->x_next;
    }
    const Eigen::Vector3d h0 = momentum(xs[k]);
    c.max_dh_plan = std::max(c.max_dh_plan, (momentum(xs[k + 1]) - h0).norm());
    c.max_dh_fine = std::max(c.max_dh_fine, (momentum(x) - h0).norm());
    const Eigen::Matrix3d R1 = rotation(x), R0 = rotation(xs[k]);
    c.pitch += log3(R1 * R0.transpose()).y();
    c.pitch_axis +=
        std::remainder(std::atan2(-R1(2, 0), R1(0, 0)) - std::atan2(-R0(2, 0), R0(0, 0)), 2 * M_PI);
  }
  return c;
}

}  // namespace stride
