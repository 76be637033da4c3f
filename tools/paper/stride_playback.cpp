#include "tools/paper/stride_playback.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "messages/policy_interpolation.hpp"
#include "messages/publisher.hpp"
#include "messages/validate.hpp"
#include "sim/sim_node.hpp"
#include "sim/simulator.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {

namespace {
// The policy τ = u_ff + K (x_ref ⊖ x) of P contact knots of a solution (states x, controls u,
// solver gains K: u = us + K (x ⊖ xs), so the policy's gain is -K), knot k at t0 + k dt.
// midpoint: the knots are semi-implicit Euler steps, q_{k+1} = q_k ⊕ dt v_{k+1}, so v_{k+1} is
// the velocity over [t_k, t_{k+1}], i.e. at its middle, and u_k the control centred at t_k
// (v_{k+1} - v_k = dt a(u_k)); the policy gets a knot every dt / 2: at t_k (q_k, (v_k + v_{k+1})/2,
// u_k, K_k) and at t_k + dt / 2 (the geodesic midpoint of q_k, q_{k+1}, v_{k+1}, the mean of u
// and K). Without it: the knots as they are (v_k at t_k), every dt.
void fillPolicy(const Model& model, const std::vector<const Eigen::VectorXd*>& x,
                const std::vector<const Eigen::VectorXd*>& u,
                const std::vector<const Eigen::MatrixXd*>& K, double t0, double dt, bool midpoint,
                msg::Policy& policy) {
  const int P = static_cast<int>(x.size()), nq = model.nq, nv = model.nv;
  const int nu = static_cast<int>(u[0]->size());
  const int knots = midpoint ? 2 * P - 1 : P;
  if (policy.knots != knots || policy.nq != nq || policy.nv != nv || policy.nu != nu)
    policy.resize(knots, nq, nv, nu);
  policy.t0 = t0;
  policy.dt = midpoint ? 0.5 * dt : dt;
  Eigen::VectorXd xr(nq + nv), dq(nv), ur(nu);
  Eigen::MatrixXd Kr(nu, 2 * nv);
  auto put = [&](int i) {
    std::copy(xr.data(), xr.data() + nq + nv, policy.xRef(i));
    std::copy(ur.data(), ur.data() + nu, policy.uFf(i));
    double* out = policy.gain(i);
    for (int r = 0; r < nu; ++r)
      for (int c = 0; c < 2 * nv; ++c) out[r * 2 * nv + c] = -Kr(r, c);
  };
  for (int k = 0; k < P; ++k) {
    const bool next = k + 1 < P;
    xr = *x[k];
    ur = *u[k];
    Kr = *K[k];
    if (midpoint && next) xr.tail(nv) = 0.5 * (x[k]->tail(nv) + x[k + 1]->tail(nv));
    put(midpoint ? 2 * k : k);
    if (!midpoint || !next) continue;
    difference(model, x[k]->head(nq), x[k + 1]->head(nq), dq);
    dq *= 0.5;
    Eigen::VectorXd q_mid(nq);
    integrate(model, x[k]->head(nq), dq, q_mid);
    xr.head(nq) = q_mid;
    xr.tail(nv) = x[k + 1]->tail(nv);
    ur = 0.5 * (*u[k] + *u[k + 1]);
    Kr = 0.5 * (*K[k] + *K[k + 1]);
    put(2 * k + 1);
  }
}
}  // namespace

const std::vector<std::string>& StrideSimResult::stepColumns() {
  static const std::vector<std::string> c = {"t",
                                             "base_x",
                                             "base_y",
                                             "base_z",
                                             "ref_x",
                                             "ref_y",
                                             "ref_z",
                                             "roll_deg",
                                             "pitch_deg",
                                             "fz_L",
                                             "fz_R",
                                             "plan_fz_L",
                                             "plan_fz_R",
                                             "cop_L_x",
                                             "cop_L_y",
                                             "cop_R_x",
                                             "cop_R_y",
                                             "plan_cop_L_x",
                                             "plan_cop_L_y",
                                             "plan_cop_R_x",
                                             "plan_cop_R_y",
                                             "foot_L_x",
                                             "foot_L_z",
                                             "foot_R_x",
                                             "foot_R_z",
                                             "plan_foot_L_x",
                                             "plan_foot_L_z",
                                             "plan_foot_R_x",
                                             "plan_foot_R_z",
                                             "foot_L_tilt_deg",
                                             "foot_R_tilt_deg",
                                             "dx_norm",
                                             "dq_norm",
                                             "dv_norm",
                                             "tau_ratio",
                                             "clamped"};
  return c;
}

namespace {
// The playback's reference, feed-forward and gains per contact sample, the policy of the whole
// run (the walk, then standing) on the plan's clock.
msg::Policy playbackPolicy(const Robot& robot, StrideProblem& sp, const StrideSolve& solve,
                           const StrideSimOptions& opt, StrideSimResult& res) {
  const Model& model = robot.model;
  const StridePlan& plan = sp.plan();
  const int nv = model.nv, N = plan.N;
  const double dt = plan.options.dt;
  msg::Policy policy;
  std::vector<const Eigen::VectorXd*> px, pu;
  std::vector<const Eigen::MatrixXd*> pK;
  if (!opt.tvlqr) {  // the offline solve's gains; past the walk the node holds its last knot
    for (int k = 0; k < N; ++k) {
      const int j = sp.contactKnot(k);
      px.push_back(&solve.xs[j]);
      pu.push_back(&solve.us[j]);
      pK.push_back(&solve.K[j]);
    }
    fillPolicy(model, px, pu, pK, 0.0, dt, opt.midpoint, policy);
    return policy;
  }
  // The tracking problem: the plan's knots (the same as the offline problem's: windowKnots from
  // sample 0), then standing on the final sample through the hold and a tail beyond it.
  const int samples = N + static_cast<int>(std::lround((opt.hold_s + opt.lqr_tail_s) / dt));
  const auto knots = StrideProblem::windowKnots(plan, 0, samples);
  const int T = static_cast<int>(knots.size()), T_off = sp.problem().horizon();
  for (int i = 0; i < T_off; ++i)
    if (knots[i].first != sp.sampleOfKnot(i) || knots[i].second != sp.isImpulse(i))
      throw std::logic_error("playbackPolicy: the tracking knots are not the plan's");
  // Standing: the walk ends in motion (the DDP's terminal state is only pulled towards rest), so
  // a reference that stops dead at the last sample asks for an impulse no sole can give. The stop
  // is planned like the walk: the plan's problem from sample N on (standing on its final contacts,
  // CoM and feet held, posture and velocities to rest, forces towards the plan's final ones, the
  // sole's centre of pressure and friction cone), box-FDDP from the DDP's final state, ending at
  // that state's configuration at rest.
  const auto t0 = std::chrono::steady_clock::now();
  const int H = samples - N;
  if (T != T_off + H)  // a touch-down at the final sample would add an impulse knot
    throw std::logic_error("playbackPolicy: the stop's knots do not follow the plan's");
  Eigen::VectorXd x_stand = solve.xs.back();
  x_stand.tail(nv).setZero();
  StrideProblem stop(robot, plan, sp.options(), N, H, x_stand);
  stop.problem().setX0(solve.xs.back());
  std::vector<Eigen::VectorXd> stop_xs(H + 1, x_stand), stop_us(H, solve.us.back());
  stop_xs[0] = solve.xs.back();
  Solver stop_solver(stop.problem(), SolverKind::BoxFddp);
  stop_solver.setControlBounds(stop.controlLower(), stop.controlUpper());
  stop_solver.setWarmStart(stop_xs, stop_us);
  stop_solver.solve(opt.stop_iterations);
  res.stop_gap = stop_solver.gap();
  std::vector<Eigen::VectorXd> xs(T + 1), us(T);
  for (int i = 0; i < T; ++i) {
    xs[i] = i <= T_off ? solve.xs[i] : stop_solver.xs()[i - T_off];
    us[i] = i < T_off ? solve.us[i] : stop_solver.us()[i - T_off];
  }
  xs[T] = stop_solver.xs()[H];
  const std::vector<Eigen::VectorXd> x_refs(xs.begin(), xs.begin() + T);
  StrideDdpOptions track = sp.options();
  track.w_posture = opt.w_track_posture;
  track.w_base_orientation = opt.w_track_base_orientation;
  track.w_velocity = opt.w_track_velocity;
  StrideProblem lqr(robot, plan, track, 0, samples, xs[T], &x_refs);
  lqr.problem().setX0(xs[0]);
  // Unconstrained gains: the node clamps the torques; box-FDDP would zero the gain rows of
  // controls at their bounds for the whole knot.
  Solver solver(lqr.problem(), SolverKind::Fddp);
  if (!solver.setWarmStart(xs, us) || !solver.computeDerivatives())
    throw std::runtime_error("playbackPolicy: derivatives at the DDP solution failed");
  bool ok = false;
  for (double mu = 1e-9; mu <= 1e3 && !ok; mu *= 10.0) {
    solver.setRegularization(mu);
    ok = solver.backwardPass();
  }
  if (!ok) throw std::runtime_error("playbackPolicy: backward pass failed");
  res.lqr_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (int k = 0; k < lqr.contactKnots(); ++k) {
    const int j = lqr.contactKnot(k);
    px.push_back(&xs[j]);
    pu.push_back(&us[j]);
    pK.push_back(&solver.K()[j]);
  }
  fillPolicy(model, px, pu, pK, 0.0, dt, opt.midpoint, policy);
  return policy;
}

// The controller's side of the lock-step: answers each state estimate with the knots of the
// playback policy from the one at or before the estimate's time (robot clock: utime_base + t).
class PlaybackAnswerer {
 public:
  PlaybackAnswerer(const msg::Policy& policy, int knots, std::int64_t utime_base, Publisher& out,
                   const std::string& policy_channel)
      : policy_(policy),
        knots_(std::min(knots, policy.knots)),
        utime_base_(utime_base),
        out_(out),
        channel_(policy_channel) {
    msg::shape(msg_, knots_, policy.nq, policy.nv, policy.nu);
    buffer_.resize(msg::policyWireSize(knots_, policy.nq, policy.nv, policy.nu));
  }
  void onState(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (!msg::decode(rbuf->data, static_cast<int>(rbuf->data_size), state_)) return;
    const double t = static_cast<double>(state_.utime - utime_base_) * 1e-6;
    const int first =
        std::clamp(static_cast<int>(std::floor(t / policy_.dt + 1e-9)), 0, policy_.knots - knots_);
    const int nx = policy_.nq + policy_.nv, nk = policy_.nu * 2 * policy_.nv;
    msg_.utime = state_.utime;
    msg_.model_hash = state_.model_hash;  // the sim's own robot: it answers in the sim's model
    msg_.session = state_.session;        // and its run (messages/README.md, "Sessions")
    msg_.knot0_utime = utime_base_ + static_cast<std::int64_t>(
                                         std::llround((policy_.t0 + first * policy_.dt) * 1e6));
    msg_.tick = ticks_++;
    msg_.t0 = policy_.t0 + first * policy_.dt;
    msg_.dt = policy_.dt;
    for (int k = 0; k < knots_; ++k) {
      std::copy(policy_.xRef(first + k), policy_.xRef(first + k) + nx, msg_.x_ref[k].begin());
      std::copy(policy_.uFf(first + k), policy_.uFf(first + k) + policy_.nu, msg_.u_ff[k].begin());
      std::copy(policy_.gain(first + k), policy_.gain(first + k) + nk, msg_.K[k].begin());
    }
    msg_.phase = 0;
    msg_.status = 0;
    const int n = msg_.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
    if (n > 0) out_.publish(channel_, buffer_.data(), n);
  }

 private:
  const msg::Policy& policy_;
  int knots_;
  std::int64_t utime_base_;
  Publisher& out_;
  std::string channel_;
  robot_state_t state_;
  policy_t msg_;
  std::vector<unsigned char> buffer_;
  std::int64_t ticks_ = 0;
};
}  // namespace

StrideSimResult simulateStrides(const Robot& robot, StrideProblem& sp, const StrideSolve& solve,
                                const StrideSimOptions& opt) {
  const bool record_steps = opt.record_steps;
  const Model& model = robot.model;
  const StridePlan& plan = sp.plan();
  const int nq = model.nq, nv = model.nv, nu = nv - 6, N = plan.N;
  const double dt = plan.options.dt;
  StrideSimResult res;
  const msg::Policy policy = playbackPolicy(robot, sp, solve, opt, res);

  // stride-sim's node and the playback on one in-process bus.
  lcm::LCM bus("memq://");
  if (!bus.good()) throw std::runtime_error("simulateStrides: no in-process LCM bus");
  LcmPublisher publisher(bus);
  sim::SimOptions so;
  sim::SimNodeOptions no;
  no.state_rate_hz = opt.state_rate_hz;
  no.fall.max_tilt_deg = 45.0;
  no.pushes = opt.pushes;
  sim::SimNode node(robot, so, no, publisher);
  node.subscribe(bus);
  PlaybackAnswerer answerer(policy, opt.answer_knots, no.utime_base, publisher, no.policy_channel);
  bus.subscribe(no.state_channel, &PlaybackAnswerer::onState, &answerer);
  node.reset(solve.xs[0].head(nq), solve.xs[0].tail(nv));
  const int per_state = node.stepsPerState();
  if ((opt.answer_knots - 1) * policy.dt < per_state * so.dt - 1e-9)
    throw std::invalid_argument("simulateStrides: the answers do not reach the next estimate");

  const sim::Simulator& simulator = node.simulator();
  // What the node computes, for the trace (x_ref ⊖ x, τ before clamping) and the drift.
  msg::PolicyEvaluator evaluator(model, nu);
  Eigen::VectorXd tau(nu);
  const int steps_per_knot = static_cast<int>(std::lround(dt / so.dt));
  const int total = static_cast<int>(std::lround((N * dt + opt.hold_s) / so.dt));
  std::array<double, 2> acc{0.0, 0.0};
  std::vector<std::array<Vector6d, 2>> plan_force;
  if (record_steps) plan_force = sp.forces(solve.xs, solve.us);
  Data fk(model);
  const int sole_frame[2] = {model.getFrameId(plan.feet[0]), model.getFrameId(plan.feet[1])};
  bool running = true;
  for (int s = 0; s < total && running; ++s) {
    if (s % per_state == 0) {  // lock-step: an estimate out, its answer in, before stepping on
      const std::int64_t stamp = node.publishState();
      while (!node.answered(stamp) && bus.handleTimeout(0) > 0) {
      }
      if (!node.answered(stamp)) ++res.unanswered;
    }
    const double t = simulator.time();
    evaluator.evaluate(policy, t, simulator.q(), simulator.v(), tau);
    const Eigen::VectorXd dx = evaluator.stateError();
    running = node.advance(1);
    if (record_steps) {
      const Eigen::VectorXd& q = simulator.q();
      framesForwardKinematics(model, fk, q);
      const int k = std::min(static_cast<int>(simulator.time() / dt + 1e-9), N - 1);
      const double* xk = solve.xs[sp.contactKnot(k)].data();
      std::vector<double> row = {simulator.time(), q[0], q[1], q[2], xk[0], xk[1], xk[2]};
      const Eigen::Quaterniond quat(q[6], q[3], q[4], q[5]);
      const Eigen::Vector3d ez = quat.toRotationMatrix().col(2);
      const Eigen::Vector3d ex = quat.toRotationMatrix().col(0);
      row.push_back(std::atan2(ez.y(), ez.z()) * -180.0 / M_PI);  // roll (about x)
      row.push_back(std::atan2(-ex.z(), ex.x()) * 180.0 / M_PI);  // pitch (about y)
      for (int c = 0; c < 2; ++c) row.push_back(simulator.normalForce(c));
      for (int c = 0; c < 2; ++c) row.push_back(plan_force[k][c][2]);
      // Measured centre of pressure of each sole in its frame (NaN when unloaded).
      for (int c = 0; c < 2; ++c) {
        Eigen::Vector3d num = Eigen::Vector3d::Zero();
        double fz = 0.0;
        for (size_t i = 0; i < simulator.contactPoints().size(); ++i) {
          const auto& pt = simulator.contactPoints()[i];
          if (pt.contact != c) continue;
          const Eigen::Vector3d pw = fk.oMf[pt.frame].R * pt.offset + fk.oMf[pt.frame].p;
          num += simulator.contactForces()(2, i) * pw;
          fz += simulator.contactForces()(2, i);
        }
        const SE3& M = fk.oMf[sole_frame[c]];
        const Eigen::Vector3d cop = fz > 1.0 ? Eigen::Vector3d(M.R.transpose() * (num / fz - M.p))
                                             : Eigen::Vector3d::Constant(NAN);
        row.push_back(cop.x());
        row.push_back(cop.y());
      }
      for (int c = 0; c < 2; ++c) {
        const Vector6d& f = plan_force[k][c];
        const bool loaded = f[2] > 1.0;
        row.push_back(loaded ? -f[4] / f[2] : NAN);
        row.push_back(loaded ? f[3] / f[2] : NAN);
      }
      for (int c = 0; c < 2; ++c) {
        row.push_back(fk.oMf[sole_frame[c]].p.x());
        row.push_back(fk.oMf[sole_frame[c]].p.z());
      }
      for (int c = 0; c < 2; ++c) {
        row.push_back(plan.foot[k][c].x());
        row.push_back(plan.foot[k][c].z());
      }
      for (int c = 0; c < 2; ++c)
        row.push_back(std::acos(std::clamp(fk.oMf[sole_frame[c]].R(2, 2), -1.0, 1.0)) * 180.0 /
                      M_PI);
      row.push_back(dx.norm());
      row.push_back(dx.head(nv).norm());
      row.push_back(dx.tail(nv).norm());
      double ratio = 0.0;
      for (int i = 0; i < nu; ++i)
        ratio = std::max(ratio, std::abs(tau[i]) / model.effortLimit[6 + i]);
      row.push_back(ratio);
      row.push_back(ratio > 1.0 ? 1.0 : 0.0);
      for (int i = 0; i < 2 * nv; ++i) row.push_back(dx[i]);
      for (int i = 0; i < nu; ++i) row.push_back(tau[i]);
      res.steps.push_back(std::move(row));
    }
    for (int c = 0; c < 2; ++c) {
      const double f = simulator.normalForce(c);
      res.peak_normal_force[c] = std::max(res.peak_normal_force[c], f);
      acc[c] += f / steps_per_knot;
    }
    const Eigen::VectorXd& q = simulator.q();
    // Drift: from the base position the policy asked for at the start of the step (the DDP
    // solution's during the walk, the planned stop's after it).
    res.final_base_error = (q.head<3>() - evaluator.qRef().head<3>()).norm();
    res.max_base_error = std::max(res.max_base_error, res.final_base_error);
    if ((s + 1) % steps_per_knot == 0) {
      for (int c = 0; c < 2; ++c)
        res.peak_normal_force_knot[c] = std::max(res.peak_normal_force_knot[c], acc[c]);
      res.trace.push_back({simulator.time(), acc[0], acc[1], q[0], q[2]});
      acc = {0.0, 0.0};
    }
  }
  const sim::SimNodeStats& st = node.stats();
  res.fell = st.fell || st.diverged;
  if (res.fell) res.fall_time = simulator.time();
  res.max_tilt_deg = st.max_tilt_deg;
  res.policies = st.policies;
  res.policies_rejected = st.policies_rejected;
  res.hold_steps = st.hold_steps;
  res.exhausted_steps = st.exhausted_steps;
  res.clamped_steps = static_cast<int>(simulator.counters().clamped_steps);
  const bool feet_down = simulator.normalForce(0) > 0.0 && simulator.normalForce(1) > 0.0;
  res.completed = !res.fell && feet_down && res.final_base_error < 0.1;
  return res;
}

}  // namespace stride
