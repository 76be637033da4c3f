#include "tools/log/session_reader.hpp"

#include <algorithm>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <utility>

#include "messages/signing.hpp"
#include "solver/contact/contact_set.hpp"
#include "stride/command_t.hpp"
#include "stride/robot_state_t.hpp"
#include "stride/terrain_t.hpp"
#include "terrain/elevation_map.hpp"

namespace stride::logs {

std::string Refusals::said() const {
  std::string s;
  for (int r = 0; r < msg::kRejectReasons; ++r)
    if (by_reason[r] > 0)
      s += (s.empty() ? "" : ", ") + std::string(msg::describe(static_cast<msg::Reject>(r))) + " " +
           std::to_string(by_reason[r]);
  return s;
}

namespace {

// A time stamp far ahead (a corrupt log) must not open millions of windows: past the cap a status
// joins the last window.
constexpr std::size_t kMaxWindows = 100000;
// Elevation maps, checked as stride-viz checks them (its bound on the cells: viz/server/feed.hpp).
constexpr int kMaxTerrainCells = 512 * 512;

// The payload of an event: a signed message's trailer stripped (messages/README.md, "Signing").
int payloadSize(const lcm::LogEvent& e) {
  return static_cast<int>(
      msg::unsignedPayloadSize(static_cast<const std::uint8_t*>(e.data), e.datalen));
}

// State estimates, checked as stride-mpc and stride-teleop check them. The summary has no robot:
// as stride-teleop, it takes the model (hash, nq, nv) of the first state that passes, a floating
// base (the summary is about where the base went), and holds every later state to it.
class StateReader {
 public:
  explicit StateReader(Refusals& refused) : refused_(refused) {}
  // True when the event is a state of the model; then state() holds it.
  bool read(const lcm::LogEvent& e) {
    using msg::Reject;
    const int size = payloadSize(e);
    Reject why = Reject::None;
    msg::WireModel model = model_;
    if (!known_) {
      msg::WireClaim claim;
      if (!msg::readStateClaim(e.data, size, claim))
        why = Reject::Undecodable;
      else if (claim.nq != claim.nv + 1 || claim.nq < 7 || claim.nv > kMaxDofs)
        why = Reject::WrongSize;  // not a floating base's state (q: position and quaternion)
      else
        model = {claim.hash, claim.nq, claim.nv, 0, "the log's first state"};
    }
    if (why == Reject::None) why = msg::checkStateWire(e.data, size, model, kMaxContacts);
    if (why == Reject::None && !msg::decode(e.data, size, state_)) why = Reject::Undecodable;
    if (why == Reject::None) why = msg::checkState(state_, true);
    if (why != Reject::None) {
      refused_.add(why);
      return false;
    }
    model_ = model;
    known_ = true;
    return true;
  }
  const robot_state_t& state() const { return state_; }

 private:
  static constexpr int kMaxDofs = 1000;  // as stride-teleop's
  msg::WireModel model_;
  bool known_ = false;
  robot_state_t state_;
  Refusals& refused_;
};

// A command from the log, accepted as the controller would accept it: sizes on the wire, then the
// decoded content, then a stamp newer than the last accepted one. Rejects are counted, not fatal.
void readCommand(const lcm::LogEvent& e, std::vector<std::int64_t>& utimes, Session& s) {
  command_t m{};
  const int size = payloadSize(e);
  if (msg::checkCommandWire(e.data, size) != msg::Reject::None || m.decode(e.data, 0, size) < 0 ||
      msg::checkCommand(m) != msg::Reject::None || (!utimes.empty() && m.utime <= utimes.back())) {
    ++s.command_rejects;
    return;
  }
  utimes.push_back(m.utime);
  CommandSample c;  // t once the first state is known
  c.vx = m.vx;
  c.vy = m.vy;
  c.yaw_rate = m.yaw_rate;
  c.gait = m.gait;
  c.body_height = m.body_height;
  c.jump_id = m.jump_id;
  s.commands.push_back(c);
}

// The newest map (true), or a refused one (false, counted).
bool readMap(const lcm::LogEvent& e, terrain::ElevationMap& map, Session& s) {
  terrain_t m;
  const int size = payloadSize(e);
  msg::Reject why = msg::checkTerrainWire(e.data, size, kMaxTerrainCells);
  if (why == msg::Reject::None && m.decode(e.data, 0, size) != size) why = msg::Reject::Undecodable;
  if (why == msg::Reject::None) why = msg::checkTerrain(m);
  if (why != msg::Reject::None) {
    s.refused_maps.add(why);
    ++s.bad_maps;
    return false;
  }
  map.origin_x = m.origin_x;
  map.origin_y = m.origin_y;
  map.resolution = m.resolution;
  map.resize(m.rows, m.cols);
  bool sizes = true;
  for (int r = 0; r < m.rows && sizes; ++r) {
    sizes = static_cast<int>(m.height[r].size()) == m.cols;
    for (int c = 0; sizes && c < m.cols; ++c) {
      map.at(r, c) = m.height[r][c];
      if (std::isfinite(m.height[r][c])) s.map_top = std::max<double>(s.map_top, m.height[r][c]);
    }
  }
  if (!sizes) {
    ++s.bad_maps;
    map.resize(0, 0);
    return false;
  }
  ++s.maps;
  return true;
}

// A signed message outside the receivers' freshness window around the logger's receive time
// (the log event's timestamp, the same wall clock the receivers judge by): refused as they refuse
// it. Only for a logger on the wall clock (lcm-logger's, the demo's): stride-drive stamps its log
// with the robot's clock, from 0, where no freshness can be judged (and no one else is on its
// in-process bus). In double: a timestamp near either end of int64 minus the clock would overflow.
bool outsideWindow(const lcm::LogEvent& e) {
  constexpr std::int64_t kWallClockSince = 1'000'000'000'000'000;  // µs: 2001-09-09
  if (e.timestamp < kWallClockSince) return false;
  msg::SignatureClaim claim;
  if (!msg::readSignatureClaim(static_cast<const std::uint8_t*>(e.data), e.datalen, claim))
    return false;
  return std::abs(static_cast<double>(claim.timestamp) - static_cast<double>(e.timestamp)) >
         static_cast<double>(msg::kFreshnessWindowMicros);
}

}  // namespace

bool readSession(const std::string& path, const SessionChannels& channels, double window,
                 const FallLimits& fall, Session& s, std::string& error) {
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    error = "cannot read '" + path + "'";
    return false;
  }
  s = Session{};
  s.z_min = INFINITY;
  s.z_max = -INFINITY;
  StateReader state_reader(s.refused_states);
  bool policy_seen = false;
  std::int64_t status_t0 = -1, last_tick = -1;
  terrain::ElevationMap map;
  std::vector<std::int64_t> command_utimes, state_gaps_us;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    const bool ours = e->channel == channels.state || e->channel == channels.terrain ||
                      e->channel == channels.command || e->channel == channels.status;
    if (ours && outsideWindow(*e)) {
      ++s.stale_signed;
      continue;
    }
    if (e->channel == channels.state) {
      if (!state_reader.read(*e)) continue;
      const robot_state_t& st = state_reader.state();
      if (s.last_state_utime >= 0 && st.utime > s.last_state_utime)
        state_gaps_us.push_back(st.utime - s.last_state_utime);
      s.last_state_utime = st.utime;
      // The terrain under the base, from the newest map that covers it (else the last known, or 0).
      if (s.maps > 0) {
        const double h = map.heightAt(st.q[0], st.q[1]);
        if (std::isfinite(h)) {
          s.ground_last = h;
          s.ground_known = true;
        }
      }
      const double z = st.q[2] - s.ground_last;
      if (s.states == 0) {
        s.x0 = st.q[0];
        s.y0 = st.q[1];
        s.z_first = z;
        s.t_first = st.utime * 1e-6;
        s.state_utime0 = st.utime;
        s.state_event0 = e->timestamp;
      }
      BaseSample b;
      b.t = static_cast<double>(st.utime - s.state_utime0) / 1e6;
      std::copy(st.q.begin(), st.q.begin() + 7, b.q.begin());
      b.ground = s.ground_last;
      // Finite velocities (checkState): they feed the segments' averages.
      std::copy(st.v.begin(), st.v.begin() + 6, b.v.begin());
      s.base_samples.push_back(b);
      s.x1 = st.q[0];
      s.y1 = st.q[1];
      s.z1 = st.q[2];
      s.t_last = st.utime * 1e-6;
      s.z_min = std::min(s.z_min, z);
      s.z_max = std::max(s.z_max, z);
      // One definition of a fall for the session and its segments (tools/log/segments.hpp).
      s.max_tilt_deg = std::max(s.max_tilt_deg, tilt(b.q) * 180.0 / M_PI);
      if (fallen(b, s.z_first, fall)) s.fell = true;
      ++s.states;
    } else if (e->channel == channels.terrain) {
      readMap(*e, map, s);
    } else if (e->channel == channels.command) {
      readCommand(*e, command_utimes, s);
    } else if (e->channel == channels.status) {
      mpc_status_t st;
      // The string lengths on the bytes first (a corrupt one would make the decoder read past the
      // event).
      const int size = payloadSize(*e);
      msg::Reject why = msg::checkStatusWire(e->data, size);
      if (why == msg::Reject::None && st.decode(e->data, 0, size) < 0)
        why = msg::Reject::Undecodable;
      if (why != msg::Reject::None) {
        s.refused_statuses.add(why);
        continue;
      }
      ++s.statuses;
      if (last_tick >= 0 && st.tick > last_tick + 1) s.lost_statuses += st.tick - last_tick - 1;
      last_tick = st.tick;
      if (window > 0.0) {
        if (status_t0 < 0) status_t0 = e->timestamp;
        const double t = 1e-6 * static_cast<double>(e->timestamp - status_t0);
        while ((s.windows.empty() || t >= s.windows.back().start + window) &&
               s.windows.size() < kMaxWindows) {
          Window w;
          w.start = s.windows.empty() ? 0.0 : s.windows.back().start + window;
          w.misses = s.last_status.deadline_misses;
          w.late = s.last_status.late_ticks;
          s.windows.push_back(std::move(w));
        }
      }
      s.last_status = st;
      noteJump(s.jumps, st.jump_id, st.jump_state, st.jump_refusal, st.utime * 1e-6);
      if (st.policy_status >= 0) {
        if (policy_seen) {
          s.latency_ms.push_back(st.tick_ms);
          s.solve_ms.push_back(st.solve_ms);
          if (st.prepared) {
            ++s.prepared;
            s.prepare_ms.push_back(st.prepare_ms);
          }
          if (!s.windows.empty()) {
            Window& w = s.windows.back();
            ++w.ticks;
            w.latency_ms.push_back(st.tick_ms);
            if (st.prepared) {
              w.prepare_ms.push_back(st.prepare_ms);
              w.work_ms.push_back(st.tick_ms + st.prepare_ms);
            }
          }
          if (st.solver_status >= 0)
            (st.step >= 1.0 ? s.full_steps : st.step > 0.0 ? s.short_steps : s.no_steps)++;
        }
        policy_seen = true;
      }
    }
  }
  if (s.states == 0) s.z_min = s.z_max = 0.0;
  if (!state_gaps_us.empty()) {
    std::vector<std::int64_t> sorted = state_gaps_us;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double period = static_cast<double>(sorted[sorted.size() / 2]);
    s.state_period_ms = period * 1e-3;
    for (const std::int64_t gap : state_gaps_us)
      if (gap > 1.5 * period) s.missing_states += std::lround(gap / period) - 1;
  }
  // Commands on the robot's clock: commands played from a script carry the stamp of the state they
  // answered, so both share the first state's origin.
  for (std::size_t i = 0; i < s.commands.size(); ++i)
    s.commands[i].t = static_cast<double>(command_utimes[i] - s.state_utime0) / 1e6;
  return true;
}

}  // namespace stride::logs
