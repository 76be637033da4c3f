#pragma once
// A slower host, played on this one for the overload tests (stride-mpc --emulate-slow-host F,
// tests/controller, tests/ocp): after each piece of the solver's work (a chunk of knots, a
// rollout) it stays busy for (F - 1) times the piece's duration, so every piece takes F times as
// long, at the solver's own granularity, and the deadline checks between pieces see it. It lives
// here and not in the solver: the numerical core only reports its pieces (WorkHook, solver.hpp).

#include "solver/ddp/solver.hpp"

namespace stride {

class SlowHost : public WorkHook {
 public:
  explicit SlowHost(double slowdown) : slowdown_(slowdown) {}
  double slowdown() const { return slowdown_; }
  void pieceDone(std::chrono::steady_clock::time_point started) override {
    if (!(slowdown_ > 1.0)) return;
    using Clock = std::chrono::steady_clock;
    const Clock::time_point now = Clock::now();
    const auto until = now + (now - started) * (slowdown_ - 1.0);
    while (Clock::now() < until) {
    }
  }

 private:
  double slowdown_;
};

}  // namespace stride
