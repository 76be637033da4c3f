// Must NOT compile (run.sh checks that it fails, and why): Stride's headers are <stride/...> for a
// user, the in-tree short form "config/robot_config.hpp" is not on a user's include path (a user's
// own config/ would collide with it; issue 34).
#include "config/robot_config.hpp"

int main() {
  return stride::loadRobot("robot.yaml").model.nq > 0 ? 0 : 1;
}
