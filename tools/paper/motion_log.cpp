#include "tools/paper/motion_log.hpp"

#include <cmath>
#include <stdexcept>

#include "config/model_hash.hpp"
#include "controller/controller_config.hpp"
#include "controller/mpc_node.hpp"
#include "messages/validate.hpp"
#include "stride/horizon_t.hpp"
#include "stride/robot_state_t.hpp"

namespace stride {

namespace {
// The channels a session uses (stride-mpc's defaults), where stride-viz looks by default.
const ControllerConfig kChannels{};
}  // namespace

std::int64_t MotionLog::utime(double t) {
  return kClockStartUtime + static_cast<std::int64_t>(std::llround(t * 1e6));
}

MotionLog::MotionLog(const std::string& path, const Robot& robot)
    : robot_(robot), hash_(modelHash(robot)), log_(path, "w"), path_(path) {
  if (!log_.good()) throw std::runtime_error("cannot write the log '" + path + "'");
  const int nu = robot.model.nv - (robot.model.hasFreeFlyer() ? 6 : 0);
  // Stamped with the first state's time: a model before the states, as the viewer reads it.
  write(kChannels.model_channel, robotModelMessage(robot, nu), kClockStartUtime);
}

template <class Message>
void MotionLog::write(const std::string& channel, const Message& m, std::int64_t utime) {
  buffer_.resize(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(buffer_.data(), 0, static_cast<int>(buffer_.size())) < 0)
    throw std::runtime_error("cannot encode a message for '" + channel + "'");
  lcm::LogEvent e{};
  e.eventnum = events_++;
  e.timestamp = utime;
  e.channel = channel;
  e.datalen = static_cast<std::int32_t>(buffer_.size());
  e.data = buffer_.data();
  if (log_.writeEvent(&e) != 0) throw std::runtime_error("cannot write to the log '" + path_ + "'");
}

void MotionLog::state(double t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                      const std::vector<bool>& closed) {
  const Model& model = robot_.model;
  if (q.size() != model.nq || v.size() != model.nv)
    throw std::invalid_argument("MotionLog::state: q or v of another size than the robot's");
  robot_state_t m;
  msg::shape(m, model.nq, model.nv, static_cast<int>(closed.size()));
  m.utime = utime(t);
  m.model_hash = hash_;
  Eigen::Map<Eigen::VectorXd>(m.q.data(), model.nq) = q;
  Eigen::Map<Eigen::VectorXd>(m.v.data(), model.nv) = v;
  // The wire asks for a unit quaternion (within 1e-4); a knot's is one up to rounding.
  if (model.hasFreeFlyer()) Eigen::Map<Eigen::Vector4d>(m.q.data() + 3).normalize();
  for (std::size_t c = 0; c < closed.size(); ++c) m.contact[c] = closed[c] ? 1 : 0;
  write(kChannels.state_channel, m, m.utime);
}

void MotionLog::plannedForces(double t, const Eigen::VectorXd& q, const std::vector<bool>& closed,
                              const std::vector<Eigen::Vector3d>& forces) {
  const Model& model = robot_.model;
  const int nc = static_cast<int>(robot_.contacts.size());
  if (q.size() != model.nq || static_cast<int>(closed.size()) != nc ||
      static_cast<int>(forces.size()) != nc)
    throw std::invalid_argument("MotionLog::plannedForces: sizes other than the robot's");
  horizon_t h;
  msg::shape(h, 1, model.nq, nc);
  h.utime = utime(t);
  h.model_hash = hash_;
  Eigen::Map<Eigen::VectorXd>(h.q[0].data(), model.nq) = q;
  if (model.hasFreeFlyer()) Eigen::Map<Eigen::Vector4d>(h.q[0].data() + 3).normalize();
  for (int c = 0; c < nc; ++c) {
    if (closed[c]) h.contact_mask[0] |= std::int32_t{1} << c;
    Eigen::Map<Eigen::Vector3d>(h.force[0].data() + 3 * c) = forces[c];
  }
  write(kChannels.horizon_channel, h, h.utime);
}

}  // namespace stride
