#include "tools/log/segments.hpp"

#include <algorithm>
#include <cmath>

namespace stride::logs {

namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

// Rotation matrix (base to world) of q[3..7) = x y z w, normalized first: estimates are unit only
// to within messages' tolerance.
Mat3 rotation(const std::array<double, 7>& q) {
  const double n = std::sqrt(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]);
  const double x = q[3] / n, y = q[4] / n, z = q[5] / n, w = q[6] / n;
  return {{{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
           {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
           {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}}};
}

std::array<double, 3> apply(const Mat3& r, double a, double b, double c) {
  return {r[0][0] * a + r[0][1] * b + r[0][2] * c, r[1][0] * a + r[1][1] * b + r[1][2] * c,
          r[2][0] * a + r[2][1] * b + r[2][2] * c};
}

bool sameCommand(const CommandSample& a, const CommandSample& b) {
  return a.vx == b.vx && a.vy == b.vy && a.yaw_rate == b.yaw_rate && a.gait == b.gait &&
         a.body_height == b.body_height && a.jump_id == b.jump_id;
}

}  // namespace

double yaw(const std::array<double, 7>& q) {
  const Mat3 r = rotation(q);
  return std::atan2(r[1][0], r[0][0]);
}

double tilt(const std::array<double, 7>& q) {
  return sim::baseTilt(q[3], q[4], q[5], q[6]);
}

std::array<double, 3> headingVelocity(const BaseSample& s) {
  const Mat3 r = rotation(s.q);
  const std::array<double, 3> lin = apply(r, s.v[0], s.v[1], s.v[2]);
  const std::array<double, 3> ang = apply(r, s.v[3], s.v[4], s.v[5]);
  const double h = std::atan2(r[1][0], r[0][0]);
  const double c = std::cos(h), sn = std::sin(h);
  return {c * lin[0] + sn * lin[1], -sn * lin[0] + c * lin[1], ang[2]};
}

bool fallen(const BaseSample& s, double first_height, const FallLimits& limits) {
  return sim::fallen(s.q[2] - s.ground, first_height, tilt(s.q), limits);
}

std::vector<Segment> segmentCommands(const std::vector<CommandSample>& commands,
                                     const std::vector<BaseSample>& states,
                                     const SegmentOptions& options) {
  std::vector<Segment> segments;
  for (std::size_t i = 0; i < commands.size(); ++i) {
    const CommandSample& c = commands[i];
    if (i > 0 && sameCommand(c, commands[i - 1])) {
      ++segments.back().commands;
      continue;
    }
    Segment s;
    s.t0 = c.t;
    s.command = {c.vx, c.vy, c.yaw_rate};
    s.gait = c.gait;
    s.body_height = c.body_height;
    s.jump_id = c.jump_id;
    s.commands = 1;
    segments.push_back(s);
  }
  const double t_end = states.empty() ? 0.0 : states.back().t;
  for (std::size_t k = 0; k < segments.size(); ++k)
    segments[k].t1 = std::max(segments[k].t0, k + 1 < segments.size() ? segments[k + 1].t0 : t_end);
  if (states.empty()) return segments;

  const double first_height = states.front().q[2] - states.front().ground;
  for (std::size_t k = 0; k < segments.size(); ++k) {
    Segment& s = segments[k];
    const bool last = k + 1 == segments.size();
    // Half-open [t0, t1) so a state on a boundary belongs to one segment; the last one keeps the
    // session's last state.
    const auto inside = [&](double t) { return t >= s.t0 && (t < s.t1 || (last && t <= s.t1)); };
    std::array<double, 3> sum{};
    auto b = std::lower_bound(states.begin(), states.end(), s.t0,
                              [](const BaseSample& x, double t) { return x.t < t; });
    for (; b != states.end() && inside(b->t); ++b) {
      if (fallen(*b, first_height, options.fall)) s.fell = true;
      if (b->t < s.t0 + options.settle) continue;
      const std::array<double, 3> h = headingVelocity(*b);
      for (int j = 0; j < 3; ++j) sum[j] += h[j];
      ++s.samples;
    }
    if (s.samples > 0)
      for (int j = 0; j < 3; ++j) s.achieved[j] = sum[j] / s.samples;
  }
  return segments;
}

std::vector<TrackingMiss> checkTracking(const std::vector<Segment>& segments,
                                        const TrackingTolerance& tolerance) {
  std::vector<TrackingMiss> misses;
  for (std::size_t k = 0; k < segments.size(); ++k) {
    const Segment& s = segments[k];
    TrackingMiss m;
    m.segment = static_cast<int>(k);
    if (s.fell) {
      m.kind = TrackingMiss::Kind::Fell;
      misses.push_back(m);
    }
    if (s.t1 - s.t0 < tolerance.min_duration || s.jump_id > 0) continue;
    if (s.samples == 0) {
      m.kind = TrackingMiss::Kind::NoSamples;
      misses.push_back(m);
      continue;
    }
    for (int j = 0; j < 3; ++j) {
      const double floor = j < 2 ? tolerance.linear : tolerance.yaw_rate;
      const double tol = std::max(tolerance.relative * std::abs(s.command[j]), floor);
      if (std::abs(s.achieved[j] - s.command[j]) > tol) {
        m.kind = TrackingMiss::Kind::Component;
        m.component = j;
        m.commanded = s.command[j];
        m.achieved = s.achieved[j];
        m.tolerance = tol;
        misses.push_back(m);
      }
    }
  }
  return misses;
}

const char* componentName(int component) {
  switch (component) {
    case 0:
      return "vx";
    case 1:
      return "vy";
    default:
      return "yaw_rate";
  }
}

Recovery recovery(const std::vector<Segment>& segments, const std::vector<BaseSample>& states,
                  double fault_end, const TrackingTolerance& tolerance,
                  const RecoveryOptions& options, const FallLimits& fall) {
  Recovery r;
  r.fault_end = fault_end;
  const std::vector<TrackingMiss> misses = checkTracking(segments, tolerance);
  for (std::size_t k = 0; k < segments.size(); ++k) {
    const Segment& s = segments[k];
    // (Times on a grid of periods: 6.0 may be 5.9999999.)
    if (s.t0 < fault_end + options.after - 1e-6 || s.t1 - s.t0 < tolerance.min_duration) continue;
    ++r.segments_after;
    r.missed_after += std::any_of(misses.begin(), misses.end(), [&](const TrackingMiss& m) {
      return m.segment == static_cast<int>(k);
    });
  }
  r.recovered = r.segments_after > 0 && r.missed_after == 0;
  if (states.empty()) return r;
  // Prefix sums of the heading-frame velocities and of the fallen states: each window is O(1).
  const std::size_t n = states.size();
  std::vector<std::array<double, 3>> sum(n + 1, std::array<double, 3>{});
  std::vector<int> fallen_count(n + 1, 0);
  const double first_height = states.front().q[2] - states.front().ground;
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<double, 3> v = headingVelocity(states[i]);
    for (int j = 0; j < 3; ++j) sum[i + 1][j] = sum[i][j] + v[j];
    fallen_count[i + 1] = fallen_count[i] + (fallen(states[i], first_height, fall) ? 1 : 0);
  }
  std::size_t end = 0, seg = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t0 = states[i].t;
    if (t0 < fault_end) continue;
    const double t1 = t0 + options.window;
    while (seg < segments.size() && segments[seg].t1 < t0) ++seg;
    if (seg == segments.size()) break;
    const Segment& s = segments[seg];
    if (s.t0 > t0 || t1 > s.t1) continue;  // the window within one command's segment
    end = std::max(end, i);
    while (end < n && states[end].t < t1) ++end;
    if (end == n) break;  // the states end before the window does
    const double count = static_cast<double>(end - i);
    if (count < 1.0 || fallen_count[end] > fallen_count[i]) continue;
    bool tracked = true;
    for (int j = 0; j < 3 && tracked; ++j) {
      const double floor = j < 2 ? tolerance.linear : tolerance.yaw_rate;
      const double tol = std::max(tolerance.relative * std::abs(s.command[j]), floor);
      tracked = std::abs((sum[end][j] - sum[i][j]) / count - s.command[j]) <= tol;
    }
    if (tracked) {
      r.time_to_tracking = t0 - fault_end;
      break;
    }
  }
  return r;
}

Motion motion(const std::vector<BaseSample>& states, double t0, double t1) {
  auto at = [&](double t) {
    return std::find_if(states.begin(), states.end(),
                        [t](const BaseSample& s) { return s.t >= t - 1e-9; });
  };
  const auto a = at(t0), b = at(t1);
  Motion m;
  if (a == states.end() || b == states.end()) return m;
  const double yaw0 = yaw(a->q), c = std::cos(yaw0), s = std::sin(yaw0);
  const double wx = b->q[0] - a->q[0], wy = b->q[1] - a->q[1];
  m.valid = true;
  m.dx = c * wx + s * wy;
  m.dy = -s * wx + c * wy;
  m.dz = b->q[2] - a->q[2];
  m.yaw = std::remainder(yaw(b->q) - yaw0, 2.0 * M_PI);
  return m;
}

void noteJump(std::vector<JumpOutcome>& jumps, int id, int state, const std::string& refusal,
              double t) {
  if (id <= 0) return;
  if (jumps.empty() || jumps.back().id != id) jumps.push_back({id, state, refusal, t, -1.0});
  JumpOutcome& j = jumps.back();
  j.state = state;
  j.refusal = refusal;
  if (state == 3 && j.t_landed < 0.0) j.t_landed = t;
}

std::string describe(const JumpOutcome& jump) {
  switch (jump.state) {
    case 1:
      return "accepted, not made yet";
    case 2:
      return "in the air";
    case 3:
      return "landed";
    case 4:
      return "refused: " + jump.refusal;
    default:
      return "?";
  }
}

}  // namespace stride::logs
