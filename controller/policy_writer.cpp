#include "controller/policy_writer.hpp"

#include <algorithm>
#include <cmath>

#include "config/model_hash.hpp"
#include "messages/hold_pd.hpp"
#include "solver/contact/knot_dynamics.hpp"

namespace stride {

// The contact limit is one number (solver/contact/contact_set.hpp): the wire's int32 masks carry
// it.
static_assert(kMaxContacts <= msg::kContactMaskBits,
              "policy_t.phase, mpc_status_t.phase, horizon_t.contact_mask: bit c for contact c");

PolicyWriter::PolicyWriter(const Robot& robot, int knots, double dt, double hold_kp, double hold_kd)
    : robot_(robot),
      nq_(robot.model.nq),
      nv_(robot.model.nv),
      nu_(actuatedDimension(robot.model)),
      dt_(dt),
      hold_kp_(hold_kp),
      hold_kd_(hold_kd) {
  msg::shape(policy_, knots, nq_, nv_, nu_);
  msg::shape(previous_, knots, nq_, nv_, nu_);
  policy_.model_hash = previous_.model_hash = stride::modelHash(robot_);
  policy_.source_id = previous_.source_id = 0;
}

void PolicyWriter::shiftClock(std::int64_t offset_us) {
  previous_.utime += offset_us;
  previous_.knot0_utime += offset_us;
}

void PolicyWriter::solved(const PolicyStamp& at, std::int32_t phase, std::int8_t status,
                          const ShootingProblem& problem, const Solver& solver) {
  const auto& xs = solver.xs();
  const auto& us = solver.us();
  const auto& K = solver.K();
  const int ndx = 2 * nv_;
  policy_.utime = at.utime;
  policy_.knot0_utime = at.utime;
  policy_.tick = at.tick;
  policy_.t0 = at.t;
  policy_.dt = dt_;
  policy_.phase = phase;
  policy_.status = status;
  int j = 0;
  for (int k = 0; k < problem.horizon() && j < policy_.knots; ++k) {
    const auto* knot = dynamic_cast<const KnotModel*>(&problem.knot(k));
    if (knot != nullptr && knot->mode() == KnotMode::Impulse) continue;
    std::copy(xs[k].data(), xs[k].data() + nq_ + nv_, policy_.x_ref[j].begin());
    std::copy(us[k].data(), us[k].data() + nu_, policy_.u_ff[j].begin());
    // The solver's law is u = us + K (x ⊖ xs); the policy's is u_ff + K' (x_ref ⊖ x), and
    // x_ref ⊖ x = -(x ⊖ x_ref) exactly (log(M⁻¹) = -log(M)), so K' = -K, row-major.
    double* out = policy_.K[j].data();
    for (int r = 0; r < nu_; ++r)
      for (int c = 0; c < ndx; ++c) out[r * ndx + c] = -K[k](r, c);
    ++j;
  }
  for (; j < policy_.knots; ++j) {  // a horizon shorter than the policy: hold its last knot
    policy_.x_ref[j] = policy_.x_ref[j - 1];
    policy_.u_ff[j] = policy_.u_ff[j - 1];
    policy_.K[j] = policy_.K[j - 1];
  }
  previous_ = policy_;  // same shapes: element copies, no allocation
  have_previous_ = true;
}

bool PolicyWriter::previous(std::int64_t utime, std::int64_t tick) {
  if (!have_previous_) return false;
  const double elapsed = (utime - previous_.knot0_utime) * 1e-6;
  const int skip = static_cast<int>(std::floor(elapsed / previous_.dt));
  if (skip < 0 || skip >= previous_.knots - 1) return false;  // nothing left to interpolate
  policy_.utime = utime;
  policy_.knot0_utime =
      previous_.knot0_utime + static_cast<std::int64_t>(std::llround(skip * previous_.dt * 1e6));
  policy_.t0 = previous_.t0 + skip * previous_.dt;
  policy_.dt = previous_.dt;
  policy_.tick = tick;
  policy_.phase = previous_.phase;
  policy_.status = kPolicyPrevious;
  for (int j = 0; j < policy_.knots; ++j) {
    const int from = std::min(j + skip, previous_.knots - 1);
    policy_.x_ref[j] = previous_.x_ref[from];
    policy_.u_ff[j] = previous_.u_ff[from];
    policy_.K[j] = previous_.K[from];
  }
  return true;
}

void PolicyWriter::hold(const PolicyStamp& at, unsigned phase, const Eigen::VectorXd& x,
                        const Eigen::VectorXd& u_hold) {
  const int ndx = 2 * nv_, base = robot_.model.hasFreeFlyer() ? 6 : 0;
  policy_.utime = at.utime;
  policy_.knot0_utime = at.utime;
  policy_.t0 = at.t;
  policy_.dt = dt_;
  policy_.tick = at.tick;
  policy_.phase = static_cast<std::int32_t>(phase);
  policy_.status = kPolicyHold;
  for (int j = 0; j < policy_.knots; ++j) {
    std::vector<double>& xr = policy_.x_ref[j];
    for (int i = 0; i < nq_; ++i) xr[i] = i < nq_ - nu_ ? x[i] : robot_.default_q[i];
    for (int i = 0; i < nv_; ++i) xr[nq_ + i] = 0.0;
    std::copy(u_hold.data(), u_hold.data() + nu_, policy_.u_ff[j].begin());
    // The robot's hold law (messages/hold_pd.hpp), sent as gains on x_ref ⊖ x.
    for (int r = 0; r < nu_; ++r)
      msg::writeJointPdRow(policy_.K[j].data() + r * ndx, nv_, base + r, hold_kp_, hold_kd_);
  }
}

bool PolicyWriter::horizon(horizon_t& h, const Planner& planner, const Solver& solver,
                           double t_state) const {
  static_assert(static_cast<int>(StanceSource::Unknown) == msg::kFootholdSources - 1,
                "horizon_t.foothold_source carries StanceSource as a number");
  // The knots' forces are those of the solver's last computation, which may be a rejected trial's
  // rollout: then nothing is written (Solver::dataAtSolution).
  if (!solver.dataAtSolution()) return false;
  const LocomotionProblem& loco = planner.problem();
  const ShootingProblem& problem = loco.problem();
  const int T = std::min(problem.horizon(), h.knots);
  const std::vector<double>& times = loco.knotTimes();
  h.utime = policy_.utime;
  h.model_hash = policy_.model_hash;
  for (int k = 0; k < T; ++k) {
    const auto& knot = static_cast<const KnotModel&>(problem.knot(k));
    const auto& data = static_cast<const KnotActionData&>(problem.data(k));
    const ContactSet& contacts = knot.contacts();
    h.t[k] = times[k] - times[0];  // knot 0 is the state, as in the policy (knot0_utime = utime)
    std::copy(solver.xs()[k].data(), solver.xs()[k].data() + nq_, h.q[k].begin());
    h.impulse[k] = knot.mode() == KnotMode::Impulse ? 1 : 0;
    h.contact_mask[k] = static_cast<std::int32_t>(loco.contactMask(k));
    // forces(): the active contacts stacked in the set's order, each its dim (force part first).
    int row = 0;
    for (int c = 0; c < contacts.size() && c < h.ncontacts; ++c) {
      double* f = h.force[k].data() + 3 * c;
      if (!contacts.isActive(c)) {
        f[0] = f[1] = f[2] = 0.0;
        continue;
      }
      for (int i = 0; i < 3; ++i) f[i] = row + i < data.nc() ? data.forces()[row + i] : 0.0;
      row += contacts[c].dim;
    }
  }
  // The touch-downs planned for the problem just solved: after the state (the stances in force or
  // lifted from are behind it) and no later than the horizon's last knot. In the capacity h was
  // shaped with (msg::shape), so that nothing is allocated.
  const std::size_t capacity = std::min({h.foothold_contact.size(), h.foothold_time.size(),
                                         h.foothold.size(), h.foothold_source.size()});
  std::size_t n = 0;
  planner.touchDowns(t_state, times[T - 1], h.ncontacts, msg::kHorizonFootholdsPerContact,
                     [&](int c, const GaitGenerator::Stance& s) {
                       if (n >= capacity) return false;
                       h.foothold_contact[n] = c;
                       h.foothold_time[n] = s.touch_down - t_state;
                       std::copy(s.p.data(), s.p.data() + 3, h.foothold[n].begin());
                       h.foothold_source[n] = static_cast<std::int8_t>(s.source);
                       ++n;
                       return true;
                     });
  h.nfootholds = static_cast<std::int32_t>(n);
  return true;
}

}  // namespace stride
