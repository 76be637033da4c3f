#include "locomotion/contact_timeline.hpp"

namespace stride {

ContactTimeline::ContactTimeline(const ContactSet& contacts)
    : nc_(contacts.size()), contact_set_(contacts) {}

int ContactTimeline::addPattern(const ContactPlan& plan) {
  patterns_.emplace_back(plan, contact_set_);
  if (n_ == 0) reset(0, 0.0);
  return static_cast<int>(patterns_.size()) - 1;
}

bool ContactTimeline::allClosed(int id, long phase) const {
  const ContactSchedule& s = patterns_[id];
  for (int c = 0; c < nc_; ++c)
    if (!s.closed(c, phase)) return false;
  return true;
}

bool ContactTimeline::standing(int id) const {
  for (int i = 0; i < patterns_[id].phases(); ++i)
    if (!allClosed(id, i)) return false;
  return true;
}

void ContactTimeline::reset(int id, double t) {
  segments_[0] = {t, id};
  n_ = 1;
}

int ContactTimeline::segmentAt(double t) const {
  int s = n_ - 1;
  while (s > 0 && t + kPlanTimeEpsilon < segments_[s].begin) --s;
  return s;
}

bool ContactTimeline::closedIn(int s, int contact, double t) const {
  return patterns_[segments_[s].pattern].closedAt(contact, t - segments_[s].begin);
}

bool ContactTimeline::closed(int contact, double t) const {
  return closedIn(segmentAt(t), contact, t);
}

unsigned ContactTimeline::mask(double t) const {
  const int s = segmentAt(t);
  unsigned m = 0;
  for (int c = 0; c < nc_; ++c)
    if (closedIn(s, c, t)) m |= 1u << c;
  return m;
}

double ContactTimeline::switchTo(int id, double t) {
  if (id < 0 || id >= patterns() || !allClosed(id, 0)) return kNever;
  // The segments up to t stay; a switch still pending after t is replaced (or cancelled).
  int keep = n_;
  while (keep > 1 && segments_[keep - 1].begin > t + kPlanTimeEpsilon) --keep;
  const Segment& now = segments_[keep - 1];
  if (now.pattern == id) {
    n_ = keep;
    return t;
  }
  double at = kNever;
  if (standing(now.pattern)) {
    at = t;
  } else {
    const ContactSchedule& s = patterns_[now.pattern];
    const double local = t - now.begin;
    const long g = s.phaseAt(local);
    if (allClosed(now.pattern, g) && local <= s.phaseStart(g) + kPlanTimeEpsilon) {
      at = t;  // right at the start of such a phase
    } else {
      const long last = s.cyclic() ? g + s.phases() : s.phases() - 1;
      for (long k = g + 1; k <= last; ++k)
        if (allClosed(now.pattern, k)) {
          at = now.begin + s.phaseStart(k);
          break;
        }
    }
  }
  if (at == kNever) return kNever;  // nothing changes
  n_ = keep;
  if (n_ == kMaxSegments) {  // drop the oldest (long past: switches are at least a phase apart)
    for (int i = 1; i < n_; ++i) segments_[i - 1] = segments_[i];
    --n_;
  }
  segments_[n_++] = {at, id};
  return at;
}

double ContactTimeline::nextChange(int contact, double t) const {
  int s = segmentAt(t);
  const bool state = closedIn(s, contact, t);
  double from = t;
  for (;;) {
    const Segment& seg = segments_[s];
    const ContactSchedule& sched = patterns_[seg.pattern];
    // Within the segment's pattern: the next phase whose state differs (one pass at most).
    double change = kNever;
    const long g = sched.phaseAt(from - seg.begin);
    const long last = sched.cyclic() ? g + sched.phases() : sched.phases() - 1;
    for (long k = g + 1; k <= last; ++k)
      if (sched.closed(contact, k) != state) {
        change = seg.begin + sched.phaseStart(k);
        break;
      }
    const double end = segmentEnd(s);
    if (change < end - kPlanTimeEpsilon) return change;
    if (end == kNever) return kNever;
    // The next segment takes over at `end`.
    ++s;
    if (closedIn(s, contact, end) != state) return end;
    from = end;
  }
}

double ContactTimeline::lastChange(int contact, double t) const {
  const int s = segmentAt(t);
  const Segment& seg = segments_[s];
  const ContactSchedule& sched = patterns_[seg.pattern];
  const long g = sched.phaseAt(t - seg.begin);
  const bool state = sched.closed(contact, g);
  for (long k = g; k > 0 && g - k < sched.phases(); --k)
    if (sched.closed(contact, k - 1) != state) return seg.begin + sched.phaseStart(k);
  return seg.begin;
}

void ContactTimeline::forget(double t) {
  int drop = 0;
  while (drop + 1 < n_ && segments_[drop + 1].begin <= t) ++drop;
  if (drop == 0) return;
  for (int i = drop; i < n_; ++i) segments_[i - drop] = segments_[i];
  n_ -= drop;
}

}  // namespace stride
