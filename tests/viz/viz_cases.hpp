#pragma once
// What the viewer's tests share: the robot, its wire model, messages of each kind encoded as they
// travel, and the session log (made by the ctest fixture viz_session_log with stride-drive, or here
// when a test binary runs alone).

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "config/model_hash.hpp"
#include "config/robot_config.hpp"
#include "controller/mpc_node.hpp"
#include "messages/validate.hpp"
#include "stride/horizon_t.hpp"
#include "stride/mpc_status_t.hpp"
#include "stride/robot_model_t.hpp"
#include "stride/terrain_t.hpp"

namespace stride::viz::test {

inline std::string quadYaml() {
  return std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml";
}

inline const Robot& quad() {
  static const Robot robot = loadRobot(quadYaml());
  return robot;
}

template <typename Message>
std::vector<unsigned char> encode(const Message& m) {
  std::vector<unsigned char> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

inline robot_model_t quadModel() {
  return robotModelMessage(quad(), quad().model.nv - 6);
}

inline robot_state_t standingState(std::int64_t utime) {
  const Robot& r = quad();
  robot_state_t s;
  msg::shape(s, r.model.nq, r.model.nv, static_cast<int>(r.contacts.size()));
  s.utime = utime;
  s.model_hash = modelHash(r);
  for (int i = 0; i < r.model.nq; ++i) s.q[i] = r.default_q[i];
  for (auto& c : s.contact) c = 1;
  return s;
}

// A horizon of `knots` knots standing still, feet alternating in pairs every 10 knots.
inline horizon_t standingHorizon(std::int64_t utime, int knots) {
  const Robot& r = quad();
  const int nc = static_cast<int>(r.contacts.size());
  horizon_t h;
  msg::shape(h, knots, r.model.nq, nc);
  h.utime = utime;
  h.model_hash = modelHash(r);
  for (int k = 0; k < knots; ++k) {
    h.t[k] = 0.01 * k;
    h.q[k].assign(r.default_q.data(), r.default_q.data() + r.model.nq);
    h.q[k][0] = 0.001 * k;
    h.contact_mask[k] = (k / 10) % 2 ? 0b1001 : 0b1111;
    for (int c = 0; c < nc; ++c) h.force[k][3 * c + 2] = 6.0 + k;
  }
  return h;
}

// The horizon's chosen footholds (issue 31): contacts 1 and 2 land 0.2 s after the state, contact
// 1 again 0.09 s later; moved by the map (source 3), blind (1), the map's nominal one (2).
inline void addFootholds(horizon_t& h) {
  h.nfootholds = 3;
  h.foothold_contact = {1, 1, 2};
  h.foothold_time = {0.2, 0.29, 0.2};
  h.foothold = {{0.05, 0.15, 0.0}, {0.15, 0.15, 0.01}, {0.25, -0.15, 0.02}};
  h.foothold_source = {3, 1, 2};
}

// An elevation map as the mock robot publishes one: rows x cols cells of 2 cm centred on (cx, cy),
// a 5 cm box step where x > 0.3 m (world), unknown cells in a 5 x 5 square at rows and cols 10-14.
inline terrain_t boxStepMap(std::int64_t utime, int rows, int cols, double cx = 0.0,
                            double cy = 0.0) {
  terrain_t m;
  msg::shape(m, rows, cols);
  m.utime = utime;
  m.resolution = 0.02;
  m.origin_x = cx - 0.5 * m.resolution * (cols - 1);
  m.origin_y = cy - 0.5 * m.resolution * (rows - 1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const bool hole = r >= 10 && r < 15 && c >= 10 && c < 15;
      m.height[r][c] = hole ? std::nanf("") : m.origin_x + c * m.resolution > 0.3 ? 0.05f : 0.0f;
    }
  return m;
}

inline std::string sessionLog() {
  const std::string log = STRIDE_VIZ_LOG;
  if (!std::filesystem::exists(log)) {
    std::filesystem::create_directories(std::filesystem::path(log).parent_path());
    const std::string config = STRIDE_CONFIG_DIR;
    const std::string cmd = std::string(STRIDE_DRIVE_BIN) + " --config " + config +
                            "/controller/stride_quad.yaml --commands " + config +
                            "/commands/stride_quad.yaml --duration 2 --log " + log + " > /dev/null";
    if (std::system(cmd.c_str()) != 0) return "";
  }
  return log;
}

}  // namespace stride::viz::test
