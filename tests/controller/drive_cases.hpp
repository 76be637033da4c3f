#pragma once
// Command scripts the lock-step closed-loop tests share (tools/drive/closed_loop.hpp).

#include "tools/drive/closed_loop.hpp"

namespace stride::drive_cases {

// Stand, trot from trot_at, forward at 0.5 m/s from walk_at, for `duration` seconds.
inline drive::Options trotForward(double duration, double trot_at, double walk_at) {
  drive::Options o;
  o.duration = duration;
  o.script.resize(3);
  o.script[1].at = trot_at;
  o.script[1].gait = "trot";
  o.script[2] = o.script[1];
  o.script[2].at = walk_at;
  o.script[2].vx = 0.5;
  return o;
}

}  // namespace stride::drive_cases
