#pragma once
// When each contact is closed, as a commanded robot plays it: a sequence of segments on the plan
// clock, each playing one contact pattern (a gait's cycle, or a planner's plan, compiled into a
// ContactSchedule) from its own start. A gait switch appends a segment that starts at the next
// instant the pattern in force enters a phase with every contact closed; every pattern a switch
// goes to starts with such a phase. So no swing straddles two patterns, and the touch-down
// before a switch and the lift-off after it belong to one pattern each.
//
// Patterns are compiled at setup; switches and queries allocate nothing (the controller's tick
// calls them).

#include <limits>
#include <vector>

#include "locomotion/contact_plan.hpp"

namespace stride {

class ContactTimeline {
 public:
  static constexpr int kMaxSegments = 8;
  static constexpr double kNever = std::numeric_limits<double>::infinity();

  explicit ContactTimeline(const ContactSet& contacts);

  // Setup (allocates): compiles a plan against the contact set and returns its id. Throws
  // std::invalid_argument for a plan the contacts cannot play (ContactPlan::validate).
  int addPattern(const ContactPlan& plan);
  int patterns() const { return static_cast<int>(patterns_.size()); }
  const ContactSchedule& pattern(int id) const { return patterns_[id]; }
  int contacts() const { return nc_; }

  // Plays pattern `id` from time t on (its phase 0 at t), forgetting every segment.
  void reset(int id, double t);
  // Switches to pattern `id` at the first instant at or after t at which the pattern in force
  // enters a phase with every contact closed (t itself when that pattern closes every contact
  // all the time: a stand). Pattern `id` plays from its phase 0 there. A switch still pending
  // after t is replaced; asking for the pattern in force cancels it. Returns the switch time, or
  // kNever, and nothing changes, when the pattern in force never closes every contact again or
  // pattern `id` does not start with every contact closed (or does not exist).
  double switchTo(int id, double t);

  int patternAt(double t) const { return segments_[segmentAt(t)].pattern; }
  // The pattern in force at t closes every contact in all its phases, and no switch follows.
  bool standsAt(double t) const {
    const int s = segmentAt(t);
    return s == n_ - 1 && standing(segments_[s].pattern);
  }
  int lastPattern() const { return segments_[n_ - 1].pattern; }
  double lastSwitch() const { return segments_[n_ - 1].begin; }

  bool closed(int contact, double t) const;
  // Bit c is set when contact c is closed at t.
  unsigned mask(double t) const;
  // The first time after t at which the contact opens or closes (kNever when it does not).
  double nextChange(int contact, double t) const;
  // The last time at or before t at which it did, looking back to the start of the segment in
  // force at t (which is returned when the contact has not changed within the segment).
  double lastChange(int contact, double t) const;

  // Forgets segments that ended before t (the controller's clock only moves forward).
  void forget(double t);

 private:
  struct Segment {
    double begin = 0.0;
    int pattern = 0;
  };
  int segmentAt(double t) const;  // the segment in force at t (the first one before its start)
  double segmentEnd(int s) const { return s + 1 < n_ ? segments_[s + 1].begin : kNever; }
  bool closedIn(int s, int contact, double t) const;
  bool allClosed(int id, long phase) const;
  bool standing(int id) const;  // every phase closes every contact

  int nc_;
  ContactSet contact_set_;
  std::vector<ContactSchedule> patterns_;
  Segment segments_[kMaxSegments];
  int n_ = 0;
};

}  // namespace stride
