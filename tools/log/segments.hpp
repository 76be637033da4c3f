#pragma once
// Command segments of a session: how well the robot followed each command it was given.
//
// A segment is a run of consecutive identical commands (a command script played by stride-teleop
// gives one per entry). For each, the base's velocity in the heading frame (the world frame turned
// by the base's yaw only, so a robot walking forward while turning keeps a constant forward
// velocity) is averaged after a settling time, and compared with the command.
//
// Free of LCM and files: inputs are plain samples, so stride-log-summary and an in-process
// closed-loop runner can both call these functions.

#include <array>
#include <string>
#include <vector>

#include "sim/fall.hpp"

namespace stride::logs {

// One base state: t [s] on the session's clock, q = [x y z, qx qy qz qw] (world), v = [base linear,
// base angular] velocity expressed in the base frame (ARCHITECTURE.md §3).
struct BaseSample {
  double t = 0.0;
  std::array<double, 7> q{0, 0, 0, 0, 0, 0, 1};
  std::array<double, 6> v{};
  // The terrain's height under the base when it is known (an elevation map in the log, the mock
  // robot's terrain), else 0: heights for the fall criterion are taken above it.
  double ground = 0.0;
};

// One command as sent: t [s] on the same clock as the states.
struct CommandSample {
  double t = 0.0;
  double vx = 0.0, vy = 0.0, yaw_rate = 0.0;  // heading frame [m/s, m/s, rad/s]
  std::string gait;
  double body_height = 0.0;
  int jump_id = 0;  // command_t.jump_id: a jump asked for (0: none)
};

// [vx, vy, yaw_rate] of the base in its heading frame: the world linear velocity turned back by
// the yaw, and the world z component of the angular velocity.
std::array<double, 3> headingVelocity(const BaseSample& s);

// Yaw (heading) of the base quaternion [rad], and its tilt: the angle between the base's z axis and
// the world's [rad].
double yaw(const std::array<double, 7>& q);
double tilt(const std::array<double, 7>& q);

// The fall criterion, the mock robot's (sim/fall.hpp: one test, one set of defaults): the base's
// height above the terrain under it below height_fraction of the first sample's, or tilted more
// than max_tilt_deg. first_height: the first sample's q[2] - ground.
using FallLimits = sim::FallLimits;
bool fallen(const BaseSample& s, double first_height, const FallLimits& limits);

struct Segment {
  double t0 = 0.0,
         t1 = 0.0;  // [s]: the run's first command; the next run's first or the last state
  std::array<double, 3> command{};  // vx, vy, yaw_rate
  std::string gait;
  double body_height = 0.0;
  int jump_id = 0;                   // a jump's segment (its command's jump_id; 0: none)
  int commands = 0;                  // command messages in the run
  int samples = 0;                   // states averaged into `achieved`
  std::array<double, 3> achieved{};  // mean heading-frame velocity (meaningful when samples > 0)
  bool fell = false;                 // a fallen state in [t0, t1]
};

struct SegmentOptions {
  double settle = 1.0;  // states from t0 + settle on are averaged: the first second is transition
  FallLimits fall;
};

// Splits the commands (in time order) into runs of identical values and measures each against the
// states (in time order; the first gives the fall criterion's reference height). A segment ends at
// the next run's first command, the last one at the last state (never before its own start).
std::vector<Segment> segmentCommands(const std::vector<CommandSample>& commands,
                                     const std::vector<BaseSample>& states,
                                     const SegmentOptions& options = {});

// Tracking check: a segment of at least min_duration misses a component when |achieved - command|
// exceeds max(relative × |command|, the component's absolute floor); a fall fails its segment, and
// so does a long segment without any state to measure. A jump's segment is not a velocity's: only
// a fall fails it (what became of the jump is the controller's status, mpc_status_t).
struct TrackingTolerance {
  double relative = 0.15;
  double linear = 0.05;       // [m/s], vx and vy
  double yaw_rate = 0.1;      // [rad/s]
  double min_duration = 2.0;  // [s]: shorter segments are all transition
};

struct TrackingMiss {
  int segment = 0;
  enum class Kind { Component, Fell, NoSamples } kind = Kind::Component;
  int component = 0;  // 0 vx, 1 vy, 2 yaw_rate (Kind::Component)
  double commanded = 0.0, achieved = 0.0, tolerance = 0.0;
};

// Every miss, in segment order; empty when every segment tracked its command.
std::vector<TrackingMiss> checkTracking(const std::vector<Segment>& segments,
                                        const TrackingTolerance& tolerance = {});

// "vx", "vy", "yaw_rate".
const char* componentName(int component);

// What became of each jump asked for, as the controller's statuses said (mpc_status_t jump_id,
// jump_state, jump_refusal): the last word on each id.
struct JumpOutcome {
  int id = 0;
  int state = 0;  // mpc_status_t.jump_state: 1 accepted, 2 in the air, 3 landed, 4 refused
  std::string refusal;
  double t = 0.0;          // [s] the first status that named it
  double t_landed = -1.0;  // [s] the first that said it landed (< 0: none)
};
// The base's motion from t0 to t1 (the states at or just after each, in time order), in the
// heading frame it had at t0: how far a jump went and how much it turned. Not valid without states
// there.
struct Motion {
  bool valid = false;
  double dx = 0.0, dy = 0.0, dz = 0.0, yaw = 0.0;  // [m, m, m, rad]
};
Motion motion(const std::vector<BaseSample>& states, double t0, double t1);

// Records one status's jump fields (id 0: none).
void noteJump(std::vector<JumpOutcome>& jumps, int id, int state, const std::string& refusal,
              double t);
// "landed", "refused: <why>", "in the air", "accepted" (and "?" for anything else).
std::string describe(const JumpOutcome& jump);

// Recovery after a fault that ended at fault_end [s] (issue 33): surviving is not recovering. Did
// control come back? Every checked segment (at least tolerance.min_duration long) that starts
// `after` s or more after the fault's end must be tracked; and the time from the fault's end to
// the first `window` of states whose mean heading-frame velocity tracks the command in force (one
// segment's, within the segments' tolerance, no fall in it).
struct RecoveryOptions {
  double after = 2.0;   // [s]
  double window = 1.0;  // [s]: a trot's cycle or two, so a step's sway averages out
};
struct Recovery {
  double fault_end = 0.0;
  int segments_after = 0;  // checked segments starting `after` or more after the fault's end
  int missed_after = 0;    // of them, missed (a component, a fall, no states)
  bool recovered = false;  // segments_after > 0 and none missed
  double time_to_tracking = -1.0;  // [s]; < 0: never tracked after the fault
};
Recovery recovery(const std::vector<Segment>& segments, const std::vector<BaseSample>& states,
                  double fault_end, const TrackingTolerance& tolerance = {},
                  const RecoveryOptions& options = {}, const FallLimits& fall = {});

}  // namespace stride::logs
