#pragma once
// Shared by the controller tests: the in-house robots' controller configurations and states.

#include <string>

#include "config/model_hash.hpp"
#include "controller/controller_config.hpp"
#include "messages/validate.hpp"

namespace stride::controller_cases {

inline std::string configPath(const std::string& robot) {
  return std::string(STRIDE_CONFIG_DIR) + "/controller/" + robot + ".yaml";
}

// A state message of the robot standing at its default posture at time utime.
inline robot_state_t standingState(const Robot& robot, std::int64_t utime) {
  robot_state_t m;
  msg::shape(m, robot.model.nq, robot.model.nv, 0);
  m.utime = utime;
  m.model_hash = modelHash(robot);
  for (int i = 0; i < robot.model.nq; ++i) m.q[i] = robot.default_q[i];
  return m;
}

}  // namespace stride::controller_cases
