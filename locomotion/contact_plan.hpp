#pragma once
// A contact plan: a sequence of phases, each with a duration and the contacts closed during it
// (a gait: trot, walk, step). Time t is measured from the plan's start; phase i covers
// [start(i), start(i) + duration_i). Past the end the last phase is held, or the plan repeats
// when cyclic.
//
// Two types: ContactPlan is the description (names, as a planner or a YAML file gives it);
// ContactSchedule is the same plan compiled against a ContactSet (contact indices, per-phase
// masks, touch-down counts), whose queries do not allocate, for the controller's tick.

#include <string>
#include <vector>

#include "solver/contact/contact_set.hpp"

namespace stride {

struct ContactPhase {
  double duration = 0.0;
  std::vector<std::string> contacts;  // closed during the phase
};

struct ContactPlan {
  std::vector<ContactPhase> phases;
  bool cyclic = false;

  // Throws std::invalid_argument naming the problem: no phase, a duration that is not positive
  // and finite, a contact absent from `contacts`, or a contact listed twice in a phase.
  void validate(const ContactSet& contacts) const;
  // Throws std::invalid_argument for no phase or a bad duration (names are not checked).
  void validateTiming() const;

  double duration() const;  // of one pass through the phases
  // Phase index at time t (t < 0: the first phase; past the end: the last, or wrapped).
  int phaseAt(double t) const;
  double phaseStart(int phase) const;  // within the first pass
  bool isClosed(const std::string& contact, double t) const;
};

// Times this close before a phase boundary count as after it: knot times t0 + k dt carry rounding
// (0.1 = 10 × 0.01 is not exact in binary).
constexpr double kPlanTimeEpsilon = 1e-9;

// The plan against a contact set. Phases are numbered globally: phase g of a cyclic plan is
// phase g mod P of pass g / P, so times far into a cyclic plan stay exact in counts.
class ContactSchedule {
 public:
  // Validates the plan (ContactPlan::validate).
  ContactSchedule(const ContactPlan& plan, const ContactSet& contacts);

  int contacts() const { return nc_; }
  int phases() const { return P_; }
  bool cyclic() const { return cyclic_; }

  // Global phase at time t (non-cyclic: at most P - 1).
  long phaseAt(double t) const;
  double phaseStart(long g) const;
  int localPhase(long g) const { return static_cast<int>(cyclic_ ? g % P_ : g); }
  bool closed(int contact, long g) const { return closed_[localPhase(g) * nc_ + contact] != 0; }
  bool closedAt(int contact, double t) const { return closed(contact, phaseAt(t)); }
  // Touch-downs of a contact (open → closed phase boundaries) at boundaries 1..g.
  long touchdowns(int contact, long g) const;

  // The open interval of a contact that is open in global phase g: it lifted off at `lift_off`
  // (0 when open from the start) after `footholds` touch-downs, and closes again at `touch_down`
  // (+infinity when it never does).
  struct Swing {
    double lift_off, touch_down;
    long footholds;
  };
  Swing swing(int contact, long g) const;

 private:
  int nc_, P_;
  bool cyclic_;
  double period_;
  std::vector<double> start_;   // P + 1 entries: phase starts in the first pass, then the period
  std::vector<char> closed_;    // P × nc
  std::vector<int> td_prefix_;  // P × nc: touch-downs at boundaries 0..i within a pass
};

}  // namespace stride
