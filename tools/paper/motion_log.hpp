#pragma once
// A planned motion written as an lcm-logger log, so that stride-viz plays it like a session
// (`stride-viz --log FILE`, viz/README.md) and the paper's snapshot figures are frames of the same
// page (tools/paper/snapshots.py). The viewer draws a robot from its robot_model_t and its own
// URDF, so the log holds what a session's log would: the robot's robot_model_t on the model
// channel, one robot_state_t per knot on the state channel (q, v, contact flags, the robot's model
// hash), and optionally one horizon_t of a single knot per knot on the horizon channel, carrying
// the contact forces the motion plans there (the page's planned-force arrows). Channels are the
// controller's defaults. Stamps are the robot's clock as stride-sim keeps it: 1 s + the motion's
// time (stride-viz places no frame stamped 0 on its timeline).

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "config/robot_config.hpp"

namespace stride {

class MotionLog {
 public:
  // The robot clock of motion time 0 [µs], as stride-sim's (SimNodeOptions::utime_base).
  static constexpr std::int64_t kClockStartUtime = 1000000;
  // The stamp of motion time t [s]: kClockStartUtime + t in µs.
  static std::int64_t utime(double t);

  // Opens `path` for writing (std::runtime_error when it cannot) and writes the robot_model_t of
  // `robot` (every joint actuated but the free-flyer). Keeps a reference to `robot`.
  MotionLog(const std::string& path, const Robot& robot);

  // The state at motion time t: q (nq) and v (nv) in the robot's wire order, and which of the
  // robot's contacts are closed (robot YAML order; empty: none reported). Stamps must increase.
  void state(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
             const std::vector<bool>& closed);
  // The forces the motion plans at time t, as a one-knot horizon_t at configuration q: one force
  // per contact (world axes [N]; zero for open contacts).
  void plannedForces(double t, const Eigen::VectorXd& q, const std::vector<bool>& closed,
                     const std::vector<Eigen::Vector3d>& forces);

  long events() const { return events_; }

 private:
  template <class Message>
  void write(const std::string& channel, const Message& m, std::int64_t utime);

  const Robot& robot_;
  std::int64_t hash_;
  lcm::LogFile log_;
  std::string path_;
  std::vector<unsigned char> buffer_;
  long events_ = 0;
};

}  // namespace stride
