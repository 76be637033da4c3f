#pragma once
// When each contact is closed, as a commanded robot plays it: a sequence of segments on the plan
// clock, each playing one contact pattern (a gait's cycle, or a planner's plan, compiled into a
// ContactSchedule) from its own start.
//
// A gait switch is per foot (issue 45: a bound or a pronk has no instant with every foot down, yet
// must be left). The new pattern's clock starts at the next phase start of the pattern in force,
// the next one with every foot down when the pattern has one within a cycle (there the switch
// changes no foot mid-step, as the switches between walking gaits always did). Each contact then
// joins the new pattern at the first instant, from that start on, at which it is closed both as it
// goes and in the new pattern; until then it plays on as before. So a switch never cuts a swing
// (a foot in the air lands as it was going to) and never makes a stance of no length; a foot down
// may stay down through a swing of the new pattern that started before it joined.
//
// Patterns are compiled at setup; switches and queries allocate nothing (the controller's tick
// calls them).

#include <limits>
#include <vector>

#include "locomotion/contact_plan.hpp"

namespace stride {

class ContactTimeline {
 public:
  static constexpr int kMaxSegments = 16;
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
  // Switches to pattern `id`, its phase 0 at the next phase start of the pattern in force at or
  // after t (t itself in a stand, or right at a phase start), the next one with every contact
  // closed when there is one within a cycle; each contact joins it as the header says. A switch
  // whose clock starts after t is pending: a new request replaces it, and asking for the pattern
  // in force cancels it. Returns the new pattern's start, or kNever, and nothing changes, when a
  // contact would never join (e.g. it is never closed in pattern `id`) or there is no pattern `id`.
  double switchTo(int id, double t);

  // The pattern whose clock has started by t (the gait in force, as the status names it; a contact
  // may still be finishing a step of the one before).
  int patternAt(double t) const { return segments_[segmentAt(t)].pattern; }
  // Every contact plays the last pattern at t, and it closes every contact in all its phases.
  bool standsAt(double t) const;
  int lastPattern() const { return segments_[n_ - 1].pattern; }
  double lastSwitch() const { return segments_[n_ - 1].begin; }
  // When contact c joins the last pattern (lastSwitch() or later).
  double lastJoin(int contact) const { return segments_[n_ - 1].join[contact]; }

  bool closed(int contact, double t) const;
  // Bit c is set when contact c is closed at t.
  unsigned mask(double t) const;
  // The first time after t at which the contact opens or closes (kNever when it does not).
  double nextChange(int contact, double t) const;
  // The last time at or before t at which it did, looking back to when the contact joined the
  // segment it plays at t (which is returned when the contact has not changed since).
  double lastChange(int contact, double t) const;

  // From t on, the pattern in force plays `shift` seconds later (earlier when negative), every
  // contact at once: a touch-down measured before or after the clock had it (Planner,
  // "landing as it happens"). False, and nothing changes, while a switch is pending or a contact
  // still plays an earlier pattern at t. A contact's last change looks back across it.
  bool retimeFrom(double t, double shift);

  // Forgets segments that ended before t (the controller's clock only moves forward).
  void forget(double t);

 private:
  struct Segment {
    double begin = 0.0;  // the pattern's phase 0
    int pattern = 0;
    // When each contact starts playing it (>= begin); kNever: a later segment took the contact
    // before it joined this one, so it never plays it.
    double join[kMaxContacts] = {};
    bool retime = false;  // made by retimeFrom: the same pattern, moved in time
  };
  int segmentAt(double t) const;  // the segment whose clock has started by t (the first one before)
  int segmentAt(int contact, double t) const;  // the segment contact plays at t
  // When contact leaves segment s for a later one (kNever: never).
  double leaves(int contact, int s) const;
  bool closedIn(int s, int contact, double t) const;
  // The first change of contact in pattern `id` played from `begin`, after t (kNever: none).
  double changeAfter(int id, double begin, int contact, double t) const;
  bool allClosed(int id, long phase) const;
  bool standing(int id) const;  // every phase closes every contact

  int nc_;
  ContactSet contact_set_;
  std::vector<ContactSchedule> patterns_;
  Segment segments_[kMaxSegments];
  int n_ = 0;
};

}  // namespace stride
