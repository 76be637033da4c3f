#pragma once
// Disturbances the mock robot can add between its physics and the controller (ARCHITECTURE.md §6):
// publication delay, dropped messages and pushes (what the robot senses: sim/sensing.hpp). Each is
// small, deterministic for a given seed, and allocates nothing after construction.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "solver/multibody/model.hpp"

namespace stride::sim {

// The state as it was `delay` pushes ago: a ring buffer of delay + 1 stamped states.
class StateDelay {
 public:
  StateDelay(int nq, int nv, int delay);
  void push(double time, const Eigen::Ref<const Eigen::VectorXd>& q,
            const Eigen::Ref<const Eigen::VectorXd>& v);
  // False until `delay` + 1 states were pushed; then writes the oldest of them.
  bool delayed(double& time, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> v) const;
  int delay() const { return delay_; }
  void clear() { count_ = 0; }

 private:
  int delay_;
  int head_ = 0;           // next slot to write
  int count_ = 0;          // states held, up to delay + 1
  Eigen::MatrixXd q_, v_;  // one column per slot
  Eigen::VectorXd t_;
};

// Drops each message independently with probability p.
class MessageDropper {
 public:
  MessageDropper(double probability, std::uint64_t seed);
  bool drop();
  std::int64_t dropped() const { return dropped_; }

 private:
  double probability_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::int64_t dropped_ = 0;
};

// A push: a constant world force (and moment) on the base over [start, start + duration).
struct Push {
  double start = 0.0;
  double duration = 0.0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   // world axes, at the base origin
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  // world axes, about the base origin
};

// A push from the command line's "start:duration:fx,fy,fz" (seconds, newtons, world axes); false
// when the text is not that, the duration not positive or a number not finite.
bool parsePush(const std::string& text, Push& push);

struct PushSchedule {
  std::vector<Push> pushes;
  // The sum of the pushes active at time t, [force; moment] (Simulator::applyExternalWrench).
  Vector6d wrenchAt(double t) const;
  // The end of the active push that ends last, or t when none is active.
  double activeUntil(double t) const;
};

}  // namespace stride::sim
