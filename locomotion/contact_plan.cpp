#include "locomotion/contact_plan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace stride {

namespace {
// Phase index of time t within phases starting at `starts` (P + 1 entries, the last the end):
// t < 0 gives 0, t at or past the end gives P - 1.
int localPhaseAt(const std::vector<double>& starts, double t) {
  const int P = static_cast<int>(starts.size()) - 1;
  int i = 0;
  while (i + 1 < P && t >= starts[i + 1]) ++i;
  return i;
}

std::vector<double> phaseStarts(const ContactPlan& plan) {
  std::vector<double> s(plan.phases.size() + 1, 0.0);
  for (size_t i = 0; i < plan.phases.size(); ++i) s[i + 1] = s[i] + plan.phases[i].duration;
  return s;
}
}  // namespace

void ContactPlan::validateTiming() const {
  if (phases.empty()) throw std::invalid_argument("ContactPlan: the plan has no phase");
  for (size_t i = 0; i < phases.size(); ++i) {
    const double d = phases[i].duration;
    if (!std::isfinite(d) || !(d > 0.0))
      throw std::invalid_argument("ContactPlan: phase " + std::to_string(i) + " has duration " +
                                  std::to_string(d) + " (must be positive and finite)");
  }
}

void ContactPlan::validate(const ContactSet& contacts) const {
  validateTiming();
  for (size_t i = 0; i < phases.size(); ++i) {
    const auto& names = phases[i].contacts;
    for (size_t j = 0; j < names.size(); ++j) {
      if (contacts.find(names[j]) < 0)
        throw std::invalid_argument("ContactPlan: phase " + std::to_string(i) +
                                    " closes contact '" + names[j] +
                                    "', which the contact set does not have");
      if (std::find(names.begin(), names.begin() + j, names[j]) != names.begin() + j)
        throw std::invalid_argument("ContactPlan: phase " + std::to_string(i) + " lists contact '" +
                                    names[j] + "' twice");
    }
  }
}

double ContactPlan::duration() const {
  double d = 0.0;
  for (const ContactPhase& p : phases) d += p.duration;
  return d;
}

int ContactPlan::phaseAt(double t) const {
  validateTiming();
  const std::vector<double> s = phaseStarts(*this);
  t += kPlanTimeEpsilon;
  if (cyclic && t >= 0.0) t = std::fmod(t, s.back());
  return localPhaseAt(s, t);
}

double ContactPlan::phaseStart(int phase) const {
  if (phase < 0 || phase >= static_cast<int>(phases.size()))
    throw std::invalid_argument("ContactPlan::phaseStart: no phase " + std::to_string(phase));
  return phaseStarts(*this)[phase];
}

bool ContactPlan::isClosed(const std::string& contact, double t) const {
  const auto& names = phases[phaseAt(t)].contacts;
  return std::find(names.begin(), names.end(), contact) != names.end();
}

ContactSchedule::ContactSchedule(const ContactPlan& plan, const ContactSet& contacts)
    : nc_(contacts.size()),
      P_(static_cast<int>(plan.phases.size())),
      cyclic_(plan.cyclic),
      period_(0.0) {
  plan.validate(contacts);
  start_ = phaseStarts(plan);
  period_ = start_.back();
  closed_.assign(P_ * nc_, 0);
  for (int i = 0; i < P_; ++i)
    for (const std::string& name : plan.phases[i].contacts)
      closed_[i * nc_ + contacts.find(name)] = 1;
  // A touch-down at boundary i: closed in phase i, open in the phase before (across the wrap for
  // a cyclic plan; boundary 0 of a plan that does not repeat is its start, not a touch-down).
  td_prefix_.assign(P_ * nc_, 0);
  for (int c = 0; c < nc_; ++c)
    for (int i = 0; i < P_; ++i) {
      const bool has_prev = i > 0 || cyclic_;
      const int prev = (i + P_ - 1) % P_;
      const int td = has_prev && closed_[i * nc_ + c] && !closed_[prev * nc_ + c];
      td_prefix_[i * nc_ + c] = (i > 0 ? td_prefix_[(i - 1) * nc_ + c] : 0) + td;
    }
}

long ContactSchedule::phaseAt(double t) const {
  t += kPlanTimeEpsilon;
  if (!cyclic_ || t < 0.0) return localPhaseAt(start_, t);
  const double pass = std::floor(t / period_);
  return static_cast<long>(pass) * P_ + localPhaseAt(start_, t - pass * period_);
}

double ContactSchedule::phaseStart(long g) const {
  if (!cyclic_) return start_[g];
  return static_cast<double>(g / P_) * period_ + start_[g % P_];
}

long ContactSchedule::touchdowns(int contact, long g) const {
  const long pass = cyclic_ ? g / P_ : 0;
  const int i = localPhase(g);
  const int per_pass = td_prefix_[(P_ - 1) * nc_ + contact];
  const int at_start = td_prefix_[contact];  // boundary 0 of the first pass is not a touch-down
  return pass * per_pass + td_prefix_[i * nc_ + contact] - at_start;
}

ContactSchedule::Swing ContactSchedule::swing(int contact, long g) const {
  // Back to the first open phase of this run (at most one pass), forward to the next closed one.
  long lo = g;
  while (lo > 0 && g - lo < P_ && !closed(contact, lo - 1)) --lo;
  const long last = cyclic_ ? g + P_ : P_ - 1;
  long td = g + 1;
  while (td <= last && !closed(contact, td)) ++td;
  Swing s;
  s.lift_off = phaseStart(lo);
  s.touch_down = td <= last ? phaseStart(td) : std::numeric_limits<double>::infinity();
  s.footholds = touchdowns(contact, lo);
  return s;
}

}  // namespace stride
