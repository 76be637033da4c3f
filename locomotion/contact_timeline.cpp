#include "locomotion/contact_timeline.hpp"

#include <algorithm>
#include <stdexcept>

namespace stride {

namespace {
// How many state changes a switch looks through for the instant a contact joins: more than any
// two gaits' cycles hold before their feet are both down (a bound against a walk: four).
constexpr int kJoinSearch = 64;
}  // namespace

ContactTimeline::ContactTimeline(const ContactSet& contacts)
    : nc_(contacts.size()), contact_set_(contacts) {
  if (nc_ > kMaxContacts)
    throw std::invalid_argument("ContactTimeline: at most " + std::to_string(kMaxContacts) +
                                " contacts");
}

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
  segments_[0].begin = t;
  segments_[0].pattern = id;
  segments_[0].retime = false;
  std::fill(segments_[0].join, segments_[0].join + kMaxContacts, t);
  n_ = 1;
}

int ContactTimeline::segmentAt(double t) const {
  int s = n_ - 1;
  while (s > 0 && t + kPlanTimeEpsilon < segments_[s].begin) --s;
  return s;
}

int ContactTimeline::segmentAt(int contact, double t) const {
  int s = n_ - 1;
  while (s > 0 && !(segments_[s].join[contact] <= t + kPlanTimeEpsilon)) --s;
  return s;
}

double ContactTimeline::leaves(int contact, int s) const {
  // Joins of one contact increase along the segments it plays (a switch takes the contact from
  // every earlier segment it had not joined yet), so the next finite one is where it goes.
  for (int k = s + 1; k < n_; ++k)
    if (segments_[k].join[contact] != kNever) return segments_[k].join[contact];
  return kNever;
}

bool ContactTimeline::closedIn(int s, int contact, double t) const {
  return patterns_[segments_[s].pattern].closedAt(contact, t - segments_[s].begin);
}

bool ContactTimeline::closed(int contact, double t) const {
  return closedIn(segmentAt(contact, t), contact, t);
}

unsigned ContactTimeline::mask(double t) const {
  unsigned m = 0;
  for (int c = 0; c < nc_; ++c)
    if (closed(c, t)) m |= 1u << c;
  return m;
}

bool ContactTimeline::standsAt(double t) const {
  for (int c = 0; c < nc_; ++c)
    if (segmentAt(c, t) != n_ - 1) return false;
  return standing(segments_[n_ - 1].pattern);
}

double ContactTimeline::changeAfter(int id, double begin, int contact, double t) const {
  const ContactSchedule& s = patterns_[id];
  const long g = s.phaseAt(t - begin);
  const bool state = s.closed(contact, g);
  const long last = s.cyclic() ? g + s.phases() : s.phases() - 1;
  for (long k = g + 1; k <= last; ++k)
    if (s.closed(contact, k) != state) return begin + s.phaseStart(k);
  return kNever;
}

double ContactTimeline::switchTo(int id, double t) {
  if (id < 0 || id >= patterns()) return kNever;
  // The segments whose clock has started by t stay; a pending one is replaced (or cancelled).
  int keep = n_;
  while (keep > 1 && segments_[keep - 1].begin > t + kPlanTimeEpsilon) --keep;
  const Segment& now = segments_[keep - 1];
  if (now.pattern == id) {
    n_ = keep;
    return t;
  }
  // The new pattern's start: the next phase start of the one in force, preferring one with every
  // contact closed within a cycle.
  double at = t;
  if (!standing(now.pattern)) {
    const ContactSchedule& s = patterns_[now.pattern];
    const double local = t - now.begin;
    const long g = s.phaseAt(local);
    const bool at_start = local <= s.phaseStart(g) + kPlanTimeEpsilon;
    const long first = at_start ? g : g + 1;
    const long last = s.cyclic() ? first + s.phases() - 1 : s.phases() - 1;
    long pick = -1;
    for (long k = first; k <= last && pick < 0; ++k)
      if (allClosed(now.pattern, k)) pick = k;
    if (pick < 0 && first <= last) pick = first;
    // A non-cyclic plan in its held last phase has no start ahead: from t.
    if (pick >= 0) at = now.begin + s.phaseStart(pick);
  }
  // When each contact joins: the first instant from `at` closed as it plays now and in `id`.
  const int n_before = n_;
  n_ = keep;
  double join[kMaxContacts];
  for (int c = 0; c < nc_; ++c) {
    double u = at;
    int steps = 0;
    for (;;) {
      const bool now_closed = closed(c, u);
      const bool new_closed = patterns_[id].closedAt(c, u - at);
      if (now_closed && new_closed) break;
      double next = kNever;
      if (!now_closed) {
        const int s = segmentAt(c, u);
        next = std::min(changeAfter(segments_[s].pattern, segments_[s].begin, c, u), leaves(c, s));
      }
      if (!new_closed) next = std::min(next, changeAfter(id, at, c, u));
      if (next == kNever || ++steps > kJoinSearch) {
        n_ = n_before;  // nothing changes
        return kNever;
      }
      u = next;
    }
    join[c] = u;
  }
  if (n_ == kMaxSegments) {  // drop the oldest (long past: switches are at least a phase apart)
    for (int i = 1; i < n_; ++i) segments_[i - 1] = segments_[i];
    --n_;
  }
  Segment& added = segments_[n_++];
  added.begin = at;
  added.pattern = id;
  added.retime = false;
  for (int c = 0; c < nc_; ++c) {
    added.join[c] = join[c];
    // A contact that had not joined an earlier segment by now never will.
    for (int k = 0; k + 1 < n_; ++k)
      if (segments_[k].join[c] != kNever && segments_[k].join[c] > join[c])
        segments_[k].join[c] = kNever;
  }
  return at;
}

double ContactTimeline::nextChange(int contact, double t) const {
  int s = segmentAt(contact, t);
  const bool state = closedIn(s, contact, t);
  double from = t;
  for (;;) {
    const Segment& seg = segments_[s];
    const double change = changeAfter(seg.pattern, seg.begin, contact, from);
    const double end = leaves(contact, s);
    if (change < end - kPlanTimeEpsilon) return change;
    if (end == kNever) return kNever;
    // The next segment takes the contact over at `end`.
    s = segmentAt(contact, end);
    if (closedIn(s, contact, end) != state) return end;
    from = end;
  }
}

double ContactTimeline::lastChange(int contact, double t) const {
  for (int guard = 0; guard < kMaxSegments; ++guard) {
    const int s = segmentAt(contact, t);
    const Segment& seg = segments_[s];
    const ContactSchedule& sched = patterns_[seg.pattern];
    const double joined = s == 0 ? seg.begin : seg.join[contact];
    const long g = sched.phaseAt(t - seg.begin);
    const bool state = sched.closed(contact, g);
    for (long k = g; k > 0 && g - k < sched.phases(); --k)
      if (sched.closed(contact, k - 1) != state) {
        if (seg.begin + sched.phaseStart(k) > joined) return seg.begin + sched.phaseStart(k);
        break;
      }
    // A retime changes no contact where its state goes on: look back across it.
    if (!seg.retime || s == 0) return joined;
    const double before = joined - kPlanTimeEpsilon;
    if (closedIn(segmentAt(contact, before), contact, before) != state) return joined;
    t = before;
  }
  return t;
}

bool ContactTimeline::retimeFrom(double t, double shift) {
  const int last = n_ - 1;
  if (segments_[last].begin > t + kPlanTimeEpsilon) return false;  // a switch pending
  for (int c = 0; c < nc_; ++c)
    if (segmentAt(c, t) != last) return false;  // a foot still finishing a step of the one before
  if (n_ == kMaxSegments) {
    for (int i = 1; i < n_; ++i) segments_[i - 1] = segments_[i];
    --n_;
  }
  Segment moved = segments_[n_ - 1];
  moved.begin += shift;
  moved.retime = true;
  for (int c = 0; c < nc_; ++c) moved.join[c] = t;
  segments_[n_++] = moved;
  return true;
}

void ContactTimeline::forget(double t) {
  // The oldest segment goes once every contact plays a later one at t.
  while (n_ > 1) {
    bool ended = true;
    for (int c = 0; c < nc_ && ended; ++c) ended = segmentAt(c, t) > 0;
    if (!ended) break;
    for (int i = 1; i < n_; ++i) segments_[i - 1] = segments_[i];
    --n_;
  }
}

}  // namespace stride
