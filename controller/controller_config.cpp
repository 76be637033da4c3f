#include "controller/controller_config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

namespace stride {

const char* toString(SolverKind kind) {
  switch (kind) {
    case SolverKind::Ddp:
      return "ddp";
    case SolverKind::Fddp:
      return "fddp";
    case SolverKind::BoxFddp:
      return "box-fddp";
  }
  return "?";
}

std::string describeHorizon(const LocomotionOptions& h) {
  char buf[64];
  // The integrator only when it is not the default, so that Euler's line reads as it always has.
  const std::string rk4 = h.integrator == Integrator::Rk4 ? ", rk4" : "";
  if (h.grid.empty()) {
    std::snprintf(buf, sizeof buf, "%d knots of %.0f ms", h.knots, h.dt * 1e3);
    return buf + rk4;
  }
  std::string parts;
  double span = 0.0;
  for (const KnotSegment& s : h.grid) {
    std::snprintf(buf, sizeof buf, "%s%d x %.0f ms", parts.empty() ? "" : ", ", s.knots,
                  s.dt * 1e3);
    parts += buf;
    span += s.knots * s.dt;
  }
  std::snprintf(buf, sizeof buf, "%d knots, %.2f s: ", h.knots, span);
  return buf + parts + rk4;
}

namespace {

// Reads one YAML file, with the file's name and the key path in every error.
class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path) {}

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw ConfigError("controller config '" + path_ + "': " + (key.empty() ? "" : key + ": ") +
                      what);
  }

  // A typo in a key must not silently fall back to a default.
  void onlyKeys(const YAML::Node& map, const std::string& where,
                std::initializer_list<const char*> keys) const {
    if (!map) return;
    if (!map.IsMap()) fail(where, "must be a mapping");
    const std::set<std::string> allowed(keys.begin(), keys.end());
    for (const auto& kv : map) {
      const std::string k = kv.first.as<std::string>();
      if (!allowed.count(k)) fail(where.empty() ? k : where + "." + k, "unknown key");
    }
  }

  template <typename T>
  void get(const YAML::Node& map, const char* key, const std::string& where, T& out) const {
    const YAML::Node n = map[key];
    if (!n) return;
    try {
      out = n.as<T>();
    } catch (const YAML::Exception&) {
      fail(where + "." + key, "wrong type");
    }
  }

  void positive(double v, const std::string& key) const {
    if (!(v > 0.0) || !std::isfinite(v)) fail(key, "must be positive and finite");
  }
  void nonNegative(double v, const std::string& key) const {
    if (!(v >= 0.0) || !std::isfinite(v)) fail(key, "must be non-negative and finite");
  }

 private:
  std::string path_;
};

}  // namespace

ControllerConfig loadControllerConfig(const std::string& yaml_path) {
  Reader r(yaml_path);
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::BadFile&) {
    r.fail("", "file does not exist or cannot be read");
  } catch (const YAML::Exception& e) {
    r.fail("", std::string("malformed YAML: ") + e.what());
  }
  if (!root.IsMap()) r.fail("", "the top level must be a mapping");
  r.onlyKeys(root, "",
             {"robot", "rate_hz", "horizon", "policy_knots", "solver", "contacts", "weights",
              "gait", "command", "jump", "lcm", "safety", "realtime", "terrain"});

  ControllerConfig c;
  c.path = yaml_path;
  if (!root["robot"]) r.fail("robot", "missing (path of the robot YAML)");
  c.robot_yaml = (std::filesystem::path(yaml_path).parent_path() / root["robot"].as<std::string>())
                     .lexically_normal()
                     .string();
  r.get(root, "rate_hz", "", c.rate_hz);
  r.positive(c.rate_hz, "rate_hz");
  r.get(root, "policy_knots", "", c.policy_knots);
  if (c.policy_knots < 2 || c.policy_knots > 64) r.fail("policy_knots", "must be in [2, 64]");

  LocomotionOptions& lo = c.locomotion;
  const YAML::Node horizon = root["horizon"];
  r.onlyKeys(horizon, "horizon", {"knots", "dt", "grid", "integrator"});
  if (horizon) {
    r.get(horizon, "knots", "horizon", lo.knots);
    r.get(horizon, "dt", "horizon", lo.dt);
    std::string integrator = toString(lo.integrator);
    r.get(horizon, "integrator", "horizon", integrator);
    if (!parseIntegrator(integrator, lo.integrator))
      r.fail("horizon.integrator", "'" + integrator + "' is not one of euler, rk4");
  }
  // A non-uniform grid: segments {knots, dt} from now on (LocomotionOptions::grid).
  if (horizon && horizon["grid"]) {
    if (horizon["knots"] || horizon["dt"])
      r.fail("horizon", "give either grid or knots and dt, not both");
    const YAML::Node grid = horizon["grid"];
    if (!grid.IsSequence() || grid.size() == 0)
      r.fail("horizon.grid", "must be a list of {knots, dt}");
    lo.knots = 0;
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const std::string where = "horizon.grid[" + std::to_string(i) + "]";
      r.onlyKeys(grid[i], where, {"knots", "dt"});
      KnotSegment seg;
      r.get(grid[i], "knots", where, seg.knots);
      r.get(grid[i], "dt", where, seg.dt);
      if (seg.knots < 1) r.fail(where + ".knots", "must be at least 1");
      r.positive(seg.dt, where + ".dt");
      lo.grid.push_back(seg);
      lo.knots += seg.knots;
    }
    lo.dt = lo.grid.front().dt;
    // The policy's knots are the horizon's first ones, evenly spaced by dt (policy_t).
    if (c.policy_knots > lo.grid.front().knots)
      r.fail("policy_knots",
             "exceeds the grid's first segment (the policy's knots are evenly "
             "spaced)");
  }
  if (lo.knots < 2 || lo.knots > 1000) r.fail("horizon.knots", "must be in [2, 1000]");
  r.positive(lo.dt, "horizon.dt");
  if (c.policy_knots > lo.knots) r.fail("policy_knots", "exceeds horizon.knots");
  // A policy lasts until the next one arrives; when states or answers are lost, until a later one
  // does. Past its end the robot stands down, and a walking robot stood down falls: the policy must
  // bridge kMinPolicyPeriods - 1 lost answers in a row (with 20 % of the states lost, 5 in a row
  // happen once in 3000 ticks; a 60 ms policy at 50 Hz fell to 3 in a row: controller/README.md,
  // "Robustness").
  if ((c.policy_knots - 1) * lo.dt < kMinPolicyPeriods / c.rate_hz - 1e-9)
    r.fail("policy_knots",
           "the policy must cover at least " + std::to_string(kMinPolicyPeriods) +
               " tick periods (" + std::to_string(kMinPolicyPeriods / c.rate_hz) +
               " s), so that the robot rides out lost states and answers; it covers " +
               std::to_string((c.policy_knots - 1) * lo.dt) + " s");

  const YAML::Node solver = root["solver"];
  r.onlyKeys(solver, "solver",
             {"kind", "max_iterations", "initial_iterations", "deadline_fraction", "threads",
              "line_search_steps", "min_regularization"});
  if (solver) {
    std::string kind = toString(c.solver);
    r.get(solver, "kind", "solver", kind);
    if (kind == "ddp")
      c.solver = SolverKind::Ddp;
    else if (kind == "fddp")
      c.solver = SolverKind::Fddp;
    else if (kind == "box-fddp")
      c.solver = SolverKind::BoxFddp;
    else
      r.fail("solver.kind", "'" + kind + "' is not one of ddp, fddp, box-fddp");
    r.get(solver, "max_iterations", "solver", c.max_iterations);
    r.get(solver, "initial_iterations", "solver", c.initial_iterations);
    r.get(solver, "deadline_fraction", "solver", c.deadline_fraction);
    r.get(solver, "threads", "solver", c.threads);
    r.get(solver, "line_search_steps", "solver", c.line_search_steps);
    r.get(solver, "min_regularization", "solver", c.min_regularization);
  }
  if (!(c.min_regularization >= 1e-12 && c.min_regularization <= 1e6))
    r.fail("solver.min_regularization", "must be in [1e-12, 1e6]");
  if (c.line_search_steps < 1 || c.line_search_steps > 30)
    r.fail("solver.line_search_steps", "must be in [1, 30]");
  if (c.max_iterations < 1) r.fail("solver.max_iterations", "must be at least 1");
  if (c.initial_iterations < 1) r.fail("solver.initial_iterations", "must be at least 1");
  if (!(c.deadline_fraction > 0.0 && c.deadline_fraction <= 1.0))
    r.fail("solver.deadline_fraction", "must be in (0, 1]");
  if (c.threads < 1 || c.threads > 64) r.fail("solver.threads", "must be in [1, 64]");

  const YAML::Node contacts = root["contacts"];
  r.onlyKeys(contacts, "contacts",
             {"mu", "min_normal_force", "swing_height", "impulses", "torque_limits",
              "torque_limit_fraction"});
  if (contacts) {
    r.get(contacts, "mu", "contacts", lo.mu);
    r.get(contacts, "min_normal_force", "contacts", lo.min_normal_force);
    r.get(contacts, "swing_height", "contacts", c.generator.swing_height);
    r.get(contacts, "impulses", "contacts", lo.impulses);
    r.get(contacts, "torque_limits", "contacts", lo.torque_limits);
    r.get(contacts, "torque_limit_fraction", "contacts", lo.torque_limit_fraction);
  }
  r.positive(lo.mu, "contacts.mu");
  if (!(lo.torque_limit_fraction > 0.0 && lo.torque_limit_fraction <= 1.0))
    r.fail("contacts.torque_limit_fraction", "must be in (0, 1]");
  r.nonNegative(lo.min_normal_force, "contacts.min_normal_force");
  r.nonNegative(c.generator.swing_height, "contacts.swing_height");
  if (c.solver == SolverKind::BoxFddp) lo.torque_limits = true;

  const YAML::Node weights = root["weights"];
  r.onlyKeys(weights, "weights",
             {"base_position", "base_orientation", "joint_position", "base_velocity",
              "joint_velocity", "control", "swing", "swing_horizontal", "swing_rotation",
              "friction", "cop", "com", "terminal_state"});
  LocomotionWeights& w = lo.weights;
  w.swing_horizontal = w.swing;
  if (weights) {
    r.get(weights, "base_position", "weights", w.base_position);
    r.get(weights, "base_orientation", "weights", w.base_orientation);
    r.get(weights, "joint_position", "weights", w.joint_position);
    r.get(weights, "base_velocity", "weights", w.base_velocity);
    r.get(weights, "joint_velocity", "weights", w.joint_velocity);
    r.get(weights, "control", "weights", w.control);
    r.get(weights, "swing", "weights", w.swing);
    r.get(weights, "swing_rotation", "weights", w.swing_rotation);
    w.swing_horizontal = w.swing;  // unless given
    r.get(weights, "swing_horizontal", "weights", w.swing_horizontal);
    r.get(weights, "friction", "weights", w.friction);
    r.get(weights, "cop", "weights", w.cop);
    r.get(weights, "com", "weights", w.com);
    r.get(weights, "terminal_state", "weights", w.terminal_state);
  }
  for (double v : {w.base_position, w.base_orientation, w.joint_position, w.base_velocity,
                   w.joint_velocity, w.control, w.swing, w.swing_horizontal, w.swing_rotation,
                   w.friction, w.cop, w.com, w.terminal_state})
    r.nonNegative(v, "weights");

  const YAML::Node gait = root["gait"];
  static const char* const kTimed[] = {"trot",  "walk",        "pace", "pronk",
                                       "bound", "flying_trot", "hop"};
  r.onlyKeys(gait, "gait",
             {"trot", "walk", "pace", "pronk", "bound", "flying_trot", "hop", "foothold_gain",
              "max_foothold_correction", "plan_file"});
  GaitConfig& g = c.gait;
  GaitGeneratorOptions& gen = c.generator;
  for (const char* name : kTimed) g.timing[name] = GaitTiming{};
  if (gait) {
    for (const char* name : kTimed) {
      const YAML::Node t = gait[name];
      const std::string where = std::string("gait.") + name;
      // A gait with flights is timed by its stances and flights, a walking gait by its all-feet
      // phases and swings (locomotion/gait.hpp).
      const char* second = hasFlight(name) ? "flight" : "swing";
      r.onlyKeys(t, where, {"support", second});
      if (!t) continue;
      double& other = hasFlight(name) ? g.timing[name].flight : g.timing[name].swing;
      r.get(t, "support", where, g.timing[name].support);
      r.get(t, second, where, other);
      r.positive(g.timing[name].support, where + ".support");
      r.positive(other, where + "." + second);
    }
    r.get(gait, "foothold_gain", "gait", gen.foothold_gain);
    r.get(gait, "max_foothold_correction", "gait", gen.max_foothold_correction);
    if (gait["foothold_gain"]) r.nonNegative(gen.foothold_gain, "gait.foothold_gain");
    r.nonNegative(gen.max_foothold_correction, "gait.max_foothold_correction");
    if (gait["plan_file"]) {
      std::string file;
      r.get(gait, "plan_file", "gait", file);
      g.plan_file =
          (std::filesystem::path(yaml_path).parent_path() / file).lexically_normal().string();
    }
  }

  const YAML::Node command = root["command"];
  r.onlyKeys(command, "command",
             {"timeout_ms", "max_velocity", "max_body_height", "acceleration", "body_height_rate"});
  CommandConfig& cmd = c.command;
  if (command) {
    double timeout_ms = cmd.timeout * 1e3;
    r.get(command, "timeout_ms", "command", timeout_ms);
    r.positive(timeout_ms, "command.timeout_ms");
    cmd.timeout = timeout_ms * 1e-3;
    auto triple = [&](const char* key, double& a, double& b, double& d) {
      if (!command[key]) return;
      std::vector<double> v;
      r.get(command, key, "command", v);
      if (v.size() != 3) r.fail(std::string("command.") + key, "must be [x, y, yaw]");
      for (double x : v) r.nonNegative(x, std::string("command.") + key);
      a = v[0];
      b = v[1];
      d = v[2];
    };
    triple("max_velocity", cmd.max_vx, cmd.max_vy, cmd.max_yaw_rate);
    triple("acceleration", cmd.accel_x, cmd.accel_y, cmd.accel_yaw);
    r.get(command, "max_body_height", "command", cmd.max_height);
    r.get(command, "body_height_rate", "command", cmd.height_rate);
  }
  r.nonNegative(cmd.max_height, "command.max_body_height");

  // What the robot can jump (locomotion/jump.hpp); without the section it does not jump.
  const YAML::Node jump = root["jump"];
  r.onlyKeys(jump, "jump",
             {"max_distance", "max_rise", "max_turn", "max_speed", "flight", "push", "landing"});
  if (jump) {
    JumpLimits& j = c.jump;
    for (const char* key : {"max_distance", "max_rise", "max_turn", "max_speed", "push", "landing"})
      if (!jump[key])
        r.fail(std::string("jump.") + key, "missing (every limit is the robot's own)");
    r.get(jump, "max_distance", "jump", j.max_distance);
    r.get(jump, "max_rise", "jump", j.max_rise);
    r.get(jump, "max_turn", "jump", j.max_turn);
    r.get(jump, "max_speed", "jump", j.max_speed);
    r.get(jump, "push", "jump", j.push);
    r.get(jump, "landing", "jump", j.landing);
    for (double v : {j.max_distance, j.max_speed, j.push, j.landing}) r.positive(v, "jump");
    r.nonNegative(j.max_rise, "jump.max_rise");
    r.nonNegative(j.max_turn, "jump.max_turn");
    if (jump["flight"]) {
      std::vector<double> f;
      r.get(jump, "flight", "jump", f);
      if (f.size() != 2 || !(f[0] > 0.0) || !(f[1] >= f[0]) || f[1] > 1.0)
        r.fail("jump.flight",
               "must be [shortest, longest] flight [s], 0 < shortest <= longest <= 1");
      j.min_flight = f[0];
      j.max_flight = f[1];
    }
  }
  for (double a : {cmd.accel_x, cmd.accel_y, cmd.accel_yaw, cmd.height_rate})
    r.positive(a, "command.acceleration / body_height_rate");
  gen.max_height = cmd.max_height;
  gen.horizon = 0.0;
  if (lo.grid.empty()) gen.horizon = lo.knots * lo.dt;
  for (const KnotSegment& seg : lo.grid) gen.horizon += seg.knots * seg.dt;
  gen.sample_dt = lo.dt;

  const YAML::Node lcm = root["lcm"];
  r.onlyKeys(lcm, "lcm",
             {"input", "output", "state", "policy", "status", "plan", "command", "model", "horizon",
              "horizon_rate_hz", "terrain", "key_file", "signature_window_s"});
  if (lcm) {
    r.get(lcm, "input", "lcm", c.input_url);
    r.get(lcm, "output", "lcm", c.output_url);
    r.get(lcm, "state", "lcm", c.state_channel);
    r.get(lcm, "policy", "lcm", c.policy_channel);
    r.get(lcm, "status", "lcm", c.status_channel);
    r.get(lcm, "plan", "lcm", c.plan_channel);
    r.get(lcm, "command", "lcm", c.command_channel);
    r.get(lcm, "model", "lcm", c.model_channel);
    r.get(lcm, "horizon", "lcm", c.horizon_channel);
    r.get(lcm, "terrain", "lcm", c.terrain_channel);
    r.get(lcm, "horizon_rate_hz", "lcm", c.horizon_rate_hz);
    r.get(lcm, "key_file", "lcm", c.key_file);
    r.get(lcm, "signature_window_s", "lcm", c.signature_window);
    // Under a millisecond would refuse a sound LAN's messages; over a minute keeps a recording
    // fresh for that long (messages/README.md, "Freshness").
    if (!(c.signature_window >= 0.001 && c.signature_window <= 60.0))
      r.fail("lcm.signature_window_s", "must be in [0.001, 60] s");
    if (!c.key_file.empty() && c.key_file.front() != '/')
      c.key_file =
          (std::filesystem::path(yaml_path).parent_path() / c.key_file).lexically_normal().string();
    if (!(c.horizon_rate_hz >= 0.0 && c.horizon_rate_hz <= c.rate_hz))
      r.fail("lcm.horizon_rate_hz", "must be in [0, rate_hz]");
  }
  for (const std::string* ch :
       {&c.state_channel, &c.policy_channel, &c.status_channel, &c.plan_channel, &c.command_channel,
        &c.model_channel, &c.horizon_channel, &c.terrain_channel})
    if (ch->empty() || ch->size() > 63) r.fail("lcm", "channel names must have 1 to 63 characters");

  const YAML::Node safety = root["safety"];
  r.onlyKeys(safety, "safety",
             {"max_state_age_ms", "fallback", "hold_kp", "hold_kd", "max_previous_ticks"});
  if (safety) {
    double age_ms = c.max_state_age * 1e3;
    r.get(safety, "max_state_age_ms", "safety", age_ms);
    r.positive(age_ms, "safety.max_state_age_ms");
    c.max_state_age = age_ms * 1e-3;
    std::string fb = "previous";
    r.get(safety, "fallback", "safety", fb);
    if (fb == "previous")
      c.fallback = Fallback::Previous;
    else if (fb == "hold")
      c.fallback = Fallback::Hold;
    else
      r.fail("safety.fallback", "'" + fb + "' is not one of previous, hold");
    r.get(safety, "hold_kp", "safety", c.hold_kp);
    r.get(safety, "hold_kd", "safety", c.hold_kd);
    r.get(safety, "max_previous_ticks", "safety", c.max_previous_ticks);
  }
  r.nonNegative(c.hold_kp, "safety.hold_kp");
  r.nonNegative(c.hold_kd, "safety.hold_kd");
  if (c.max_previous_ticks < 0) r.fail("safety.max_previous_ticks", "must be non-negative");

  const YAML::Node terrain = root["terrain"];
  // "jump" is a motion since issue 45: the map's height step that makes an edge was jump_height.
  if (terrain && terrain.IsMap() && terrain["jump_height"])
    r.fail("terrain.jump_height", "is named terrain.edge_height now (the height step of an edge)");
  r.onlyKeys(terrain, "terrain",
             {"max_map_age_ms", "max_cells", "max_slope_deg", "edge_height", "min_edge_distance",
              "edge_search_radius", "max_foothold_shift", "swing_clearance", "max_swing_height"});
  if (terrain) {
    double age_ms = c.terrain.max_map_age * 1e3;
    r.get(terrain, "max_map_age_ms", "terrain", age_ms);
    r.positive(age_ms, "terrain.max_map_age_ms");
    c.terrain.max_map_age = age_ms * 1e-3;
    r.get(terrain, "max_cells", "terrain", c.terrain.max_cells);
    if (c.terrain.max_cells < 1 || c.terrain.max_cells > 1024 * 1024)
      r.fail("terrain.max_cells", "must be in [1, 1048576]");
    terrain::SteppabilityOptions& st = c.terrain.steppability;
    double slope_deg = st.max_slope * 180.0 / M_PI;
    r.get(terrain, "max_slope_deg", "terrain", slope_deg);
    if (!(slope_deg > 0.0 && slope_deg < 90.0))
      r.fail("terrain.max_slope_deg", "must be in (0, 90)");
    st.max_slope = slope_deg * M_PI / 180.0;
    r.get(terrain, "edge_height", "terrain", st.edge_height);
    r.positive(st.edge_height, "terrain.edge_height");
    r.get(terrain, "min_edge_distance", "terrain", st.min_edge_distance);
    r.nonNegative(st.min_edge_distance, "terrain.min_edge_distance");
    st.edge_search_radius = std::max(st.edge_search_radius, st.min_edge_distance);
    r.get(terrain, "edge_search_radius", "terrain", st.edge_search_radius);
    if (!(st.edge_search_radius >= st.min_edge_distance) || !std::isfinite(st.edge_search_radius))
      r.fail("terrain.edge_search_radius", "must be finite and at least min_edge_distance");
    GaitGeneratorOptions& g = c.generator;
    r.get(terrain, "max_foothold_shift", "terrain", g.max_foothold_shift);
    r.nonNegative(g.max_foothold_shift, "terrain.max_foothold_shift");
    r.get(terrain, "swing_clearance", "terrain", g.swing_clearance);
    r.nonNegative(g.swing_clearance, "terrain.swing_clearance");
    r.get(terrain, "max_swing_height", "terrain", g.max_swing_height);
    r.nonNegative(g.max_swing_height, "terrain.max_swing_height");
  }

  const YAML::Node rt = root["realtime"];
  r.onlyKeys(rt, "realtime", {"cpu", "fifo_priority"});
  if (rt) {
    r.get(rt, "cpu", "realtime", c.cpu);
    r.get(rt, "fifo_priority", "realtime", c.fifo_priority);
  }
  if (c.fifo_priority < 0 || c.fifo_priority > 99) r.fail("realtime.fifo_priority", "0 to 99");
  return c;
}

}  // namespace stride
