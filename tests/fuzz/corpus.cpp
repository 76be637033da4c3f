// stride-fuzz-corpus: the message fuzzer's seed corpus (tests/fuzz/corpus/), written by the real
// encoders (lcm-gen's, and robotModelMessage for the model), so that it follows the messages when
// they change. One file per handler and interesting variant: valid messages of stride_quad and the
// edge cases the checks exist for. A file is the channel byte (fuzz_channels.hpp) and the payload.
//
//   stride-fuzz-corpus DIR          writes the corpus into DIR
//   stride-fuzz-corpus --check DIR  exit 1 when DIR is not exactly what it would write (the ctest
//                                   fuzz_corpus_current, on the committed corpus)
//
// The numbers are exact in binary (multiples of 2^-24 at most) so that every compiler and flag
// writes the same bytes.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/model_hash.hpp"
#include "config/robot_config.hpp"
#include "controller/mpc_node.hpp"
#include "fuzz_channels.hpp"
#include "messages/validate.hpp"
#include "stride/command_t.hpp"
#include "stride/contact_plan_t.hpp"
#include "stride/horizon_t.hpp"
#include "stride/mpc_status_t.hpp"
#include "stride/policy_t.hpp"
#include "stride/robot_model_t.hpp"
#include "stride/robot_state_t.hpp"
#include "stride/terrain_t.hpp"

namespace stride::fuzz {
namespace {

using Bytes = std::vector<unsigned char>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::int32_t kHuge = std::numeric_limits<std::int32_t>::max();
constexpr std::int32_t kMostNegative = std::numeric_limits<std::int32_t>::min();

// A value the same on every machine: rounded to a multiple of 2^-24.
double tidy(double x) {
  return std::ldexp(std::round(std::ldexp(x, 24)), -24);
}

template <typename Message>
Bytes encode(const Message& m) {
  Bytes b(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(b.data(), 0, static_cast<int>(b.size())) != static_cast<int>(b.size()))
    throw std::runtime_error("stride-fuzz-corpus: an encoder failed");
  return b;
}

// Big-endian int32 written at `at` (a count or string length of an encoded message).
Bytes poke32(Bytes b, std::size_t at, std::int32_t value) {
  std::uint32_t u;
  std::memcpy(&u, &value, 4);
  for (int i = 0; i < 4; ++i) b.at(at + i) = static_cast<unsigned char>(u >> (24 - 8 * i));
  return b;
}

class Corpus {
 public:
  explicit Corpus(const Robot& robot)
      : robot_(robot),
        hash_(modelHash(robot)),
        nq_(robot.model.nq),
        nv_(robot.model.nv),
        nu_(robot.model.nv - 6),
        nc_(static_cast<int>(robot.contacts.size())) {}

  std::map<std::string, Bytes> build() const {
    std::map<std::string, Bytes> files;
    auto add = [&files](Channel c, const std::string& variant, const Bytes& payload) {
      Bytes b{static_cast<unsigned char>(c)};
      b.insert(b.end(), payload.begin(), payload.end());
      files[std::string(name(c)) + "-" + variant] = std::move(b);
    };

    // States, as the mock robot sends them (with contact flags) and as an estimator may (without).
    // Stamps increasing in the files' name order, the replay's (stride-mpc refuses a state that is
    // not newer than the last one it accepted).
    robot_state_t s = state(1001000, false);
    add(Channel::MpcState, "standing", encode(s));
    add(Channel::MpcState, "standing_contacts", encode(state(1002000, true)));
    s = state(1000000, true);
    for (int i = 0; i < nv_; ++i) s.v[i] = 0.125 * (i % 5) - 0.25;
    s.q[0] = 0.5;
    s.contact[1] = 0;
    add(Channel::MpcState, "moving", encode(s));
    s = state(1003000, false);
    s.model_hash ^= 1;
    add(Channel::MpcState, "another_model_hash", encode(s));
    robot_state_t other;
    msg::shape(other, nq_ + 10, nv_ + 10, 0);
    other.utime = 1003000;
    other.model_hash = 42;
    other.q[6] = 1.0;
    add(Channel::MpcState, "another_robots_sizes", encode(other));
    s = state(1003000, false);
    s.q[8] = kNaN;
    add(Channel::MpcState, "nan", encode(s));
    s = state(1003000, false);
    s.q[6] = 0.5;
    add(Channel::MpcState, "quaternion_not_unit", encode(s));
    s = state(1003000, false);
    s.utime = -1;
    add(Channel::MpcState, "negative_stamp", encode(s));
    const Bytes good = encode(state(1003000, true));
    add(Channel::MpcState, "nq_2e31", poke32(good, 8 + 24, kHuge));
    add(Channel::MpcState, "truncated", Bytes(good.begin(), good.end() - 5));
    Bytes longer = good;
    longer.push_back(0);
    add(Channel::MpcState, "extra_byte", longer);
    Bytes fingerprint = good;
    fingerprint[0] ^= 0xff;
    add(Channel::MpcState, "wrong_type_hash", fingerprint);

    // Contact plans from a planner.
    contact_plan_t trot = plan({{1, 1, 1, 1}, {1, 0, 0, 1}, {1, 1, 1, 1}, {0, 1, 1, 0}}, true);
    add(Channel::MpcPlan, "trot", encode(trot));
    add(Channel::MpcPlan, "stand", encode(plan({{1, 1, 1, 1}}, false)));
    contact_plan_t unknown = trot;
    unknown.contacts[2] = "XX_foot";
    add(Channel::MpcPlan, "unknown_contact", encode(unknown));
    contact_plan_t zero = trot;
    zero.duration[1] = 0.0;
    add(Channel::MpcPlan, "zero_duration", encode(zero));
    add(Channel::MpcPlan, "name_length_negative", poke32(encode(trot), 8 + 8 + 1 + 4, -2));
    contact_plan_t early = trot;
    early.utime = std::numeric_limits<std::int64_t>::min();
    add(Channel::MpcPlan, "stamp_most_negative", encode(early));

    // Body commands from a teleop, stamped in the files' name order too.
    add(Channel::MpcCommand, "beyond_limits", encode(command(2000000, "walk", 8.0)));
    add(Channel::MpcCommand, "gait_31_characters",
        encode(command(2001000, std::string(msg::kMaxGaitName, 't'), 0.5)));
    add(Channel::MpcCommand, "gait_32_characters",
        encode(command(2002000, std::string(msg::kMaxGaitName + 1, 't'), 0.5)));
    add(Channel::MpcCommand, "gait_length_negative",
        poke32(encode(command(2003000, "trot", 0.5)), 8 + 32, kMostNegative));
    add(Channel::MpcCommand, "keep_gait", encode(command(2004000, "", 0.25)));
    add(Channel::MpcCommand, "nan", encode(command(2005000, "trot", kNaN)));
    add(Channel::MpcCommand, "stand", encode(command(2006000, "stand", 0.0)));
    add(Channel::MpcCommand, "trot", encode(command(2007000, "trot", 0.5)));
    add(Channel::MpcCommand, "unknown_gait", encode(command(2008000, "gallop", 0.5)));
    // Jumps (issue 45): one the robot makes, one beyond its reach, a NaN target, a negative id.
    command_t jump = command(2009000, "stand", 0.0);
    jump.jump_id = 1;
    jump.jump[0] = 0.25;
    jump.jump[3] = 0.5;
    add(Channel::MpcCommand, "jump", encode(jump));
    jump.utime = 2010000;
    jump.jump_id = 2;
    jump.jump[0] = 8.0;
    add(Channel::MpcCommand, "jump_beyond_reach", encode(jump));
    jump.utime = 2011000;
    jump.jump_id = 3;
    jump.jump[2] = kNaN;
    add(Channel::MpcCommand, "jump_nan", encode(jump));
    jump.utime = 2012000;
    jump.jump_id = -4;
    jump.jump[2] = 0.0;
    add(Channel::MpcCommand, "jump_id_negative", encode(jump));

    // A policy of another controller on stride-mpc's policy channel.
    add(Channel::MpcPolicy, "rival", encode(policy(1000000, 2, 7)));

    // Policies for the mock robot (its clock starts at 1 s: knot 0 there is applied at once).
    add(Channel::SimPolicy, "hold", encode(policy(1000000, 2, 1)));
    policy_t p = policy(1000000, 3, 1);
    for (int k = 0; k < p.knots; ++k) {
      p.x_ref[k][7 + 1] += 0.0625 * k;  // a hip swinging forward
      p.x_ref[k][nq_ + 2] = -0.125;     // the base sinking
      p.u_ff[k][2] = -0.25 * k;
    }
    add(Channel::SimPolicy, "moving", encode(p));
    p = policy(1000000, 2, 1);
    p.model_hash ^= 1;
    add(Channel::SimPolicy, "another_model_hash", encode(p));
    p = policy(1000000, 2, 1);
    p.K[1][5] = kNaN;
    add(Channel::SimPolicy, "nan_gain", encode(p));
    p = policy(1000000, 2, 1);
    p.dt = 0.0;
    add(Channel::SimPolicy, "dt_zero", encode(p));
    p = policy(1000000, 2, 1);
    p.knot0_utime = 0;
    add(Channel::SimPolicy, "past_its_end", encode(p));
    p = policy(1000000, 2, 1);
    p.knot0_utime = std::numeric_limits<std::int64_t>::min();
    add(Channel::SimPolicy, "knot0_most_negative", encode(p));
    p = policy(1000000, 2, 1);
    p.status = 9;
    add(Channel::SimPolicy, "status_unknown", encode(p));
    add(Channel::SimPolicy, "knots_2e31", poke32(encode(policy(1000000, 2, 1)), 8 + 64, kHuge));
    p = policy(1000000, 2, 1);
    p.session ^= 1;  // made for another run of the robot (issue 44)
    add(Channel::SimPolicy, "another_session", encode(p));

    // stride-viz (the fuzzer gave it stride_quad's model at start), and what it draws.
    const robot_model_t model = robotModelMessage(robot_, nu_);
    add(Channel::VizModel, "stride_quad", encode(model));
    robot_model_t renamed = model;
    renamed.robot = "no_such_robot";
    renamed.model_hash = 5;
    add(Channel::VizModel, "another_robot", encode(renamed));
    robot_model_t upward = model;
    upward.robot = "../../robots/stride_quad";
    add(Channel::VizModel, "name_leaving_config", encode(upward));
    add(Channel::VizModel, "name_length_negative", poke32(encode(model), 8, kMostNegative));
    add(Channel::VizModel, "njoints_2e31",
        poke32(encode(model), 8 + 4 + robot_.name.size() + 1 + 8 + 12, kHuge));
    add(Channel::VizState, "standing", encode(state(1000000, false)));
    add(Channel::VizState, "standing_contacts", encode(state(1001000, true)));
    // The next state frames the one before with the policy held (its forces estimated).
    add(Channel::VizState, "standing_contacts_next", encode(state(1002000, true)));
    add(Channel::VizPolicy, "hold", encode(policy(1000000, 2, 1)));
    // Stamps at the ends of int64 (after the horizon, before the states: the files' name order).
    p = policy(1000000, 2, 1);
    p.utime = p.knot0_utime = std::numeric_limits<std::int64_t>::max();
    add(Channel::VizPolicy, "stamps_highest", encode(p));
    p.utime = p.knot0_utime = std::numeric_limits<std::int64_t>::min();
    add(Channel::VizPolicy, "stamps_lowest", encode(p));
    add(Channel::VizHorizon, "standing", encode(horizon(1000000, 8)));
    horizon_t h = horizon(1000000, 8);
    h.contact_mask[3] = 1 << nc_;
    add(Channel::VizHorizon, "mask_of_a_fifth_contact", encode(h));
    add(Channel::VizHorizon, "knots_2e31", poke32(encode(horizon(1000000, 8)), 8 + 16, kHuge));
    // The chosen footholds (issue 31): a count of 2^31, a fifth contact's, an unknown source.
    h = horizon(1000000, 8);
    horizon_t no_footholds = h;
    no_footholds.nfootholds = 0;
    const std::size_t nfootholds_at = static_cast<std::size_t>(no_footholds.getEncodedSize()) - 4;
    add(Channel::VizHorizon, "nfootholds_2e31", poke32(encode(h), nfootholds_at, kHuge));
    h.foothold_contact[1] = nc_;
    add(Channel::VizHorizon, "foothold_of_a_fifth_contact", encode(h));
    h = horizon(1000000, 8);
    h.foothold_source[0] = msg::kFootholdSources;
    add(Channel::VizHorizon, "foothold_source_unknown", encode(h));
    const mpc_status_t st = status(1000000);
    add(Channel::VizStatus, "trot", encode(st));
    mpc_status_t refusing = status(1005000);
    refusing.wrong_model = 3;
    refusing.wrong_model_cause =
        "expected nq 19, nv 18 (stride_quad, hash 0123456789abcdef), got nq 29, nv 28";
    add(Channel::VizStatus, "wrong_model_cause", encode(refusing));
    // The string lengths of mpc_status_t: wrong_model_cause's, and gait's (after the cause).
    const std::size_t cause_at =
        8 + 8 + 8 + 8 + 8 + 1 + 8 + 4 + 4 + 8 + 8 + 8 + 8 + 4 + 8 + 1 + 8 * 8;
    add(Channel::VizStatus, "cause_length_most_negative",
        poke32(encode(st), cause_at, kMostNegative));
    add(Channel::VizStatus, "cause_length_zero", poke32(encode(st), cause_at, 0));
    const Bytes trot_status = encode(st);
    add(Channel::VizStatus, "gait_length_past_end",
        poke32(trot_status, trot_status.size() - 57 - 5 - 4, 1000));  // 57: the fields after gait
    add(Channel::VizCommand, "trot", encode(command(2000000, "trot", 0.5)));
    // Elevation maps (stamps increasing in the files' name order: a map older than the last one
    // accepted is refused): a box step with unknown cells, and the cases the checks exist for.
    constexpr std::size_t rows_at = 8 + 8 + 3 * 8;
    add(Channel::VizTerrain, "box_step", encode(terrain(1000000, 12, 16)));
    add(Channel::VizTerrain, "box_step_older", encode(terrain(999000, 12, 16)));
    add(Channel::VizTerrain, "cols_2e31",
        poke32(encode(terrain(1001000, 12, 16)), rows_at + 4, kHuge));
    add(Channel::VizTerrain, "cols_zero", poke32(encode(terrain(1001000, 12, 16)), rows_at + 4, 0));
    terrain_t t = terrain(1001000, 12, 16);
    t.height[5][7] = std::numeric_limits<float>::infinity();
    add(Channel::VizTerrain, "inf_height", encode(t));
    t = terrain(1001000, 12, 16);
    t.resolution = 0.0;
    add(Channel::VizTerrain, "resolution_zero", encode(t));
    add(Channel::VizTerrain, "rows_2e31", poke32(encode(terrain(1001000, 12, 16)), rows_at, kHuge));
    // 65536 x 65536 cells wrap to 0 in 32 bits: a size check by that product would take the
    // header alone (a 1 x 1 map without its cell) for a map of no cells.
    const Bytes one = encode(terrain(1001000, 1, 1));
    add(Channel::VizTerrain, "rows_cols_wrapping",
        poke32(poke32(Bytes(one.begin(), one.end() - 4), rows_at, 65536), rows_at + 4, 65536));
    const Bytes map = encode(terrain(1001000, 12, 16));
    add(Channel::VizTerrain, "truncated", Bytes(map.begin(), map.end() - 3));
    // The same maps to the controller (MpcNode::onTerrain), and a resolution too fine to be one
    // (a denormal: grid coordinates would overflow).
    add(Channel::MpcTerrain, "box_step", encode(terrain(1000000, 12, 16)));
    add(Channel::MpcTerrain, "box_step_older", encode(terrain(999000, 12, 16)));
    add(Channel::MpcTerrain, "cols_2e31",
        poke32(encode(terrain(1001000, 12, 16)), rows_at + 4, kHuge));
    add(Channel::MpcTerrain, "rows_cols_wrapping",
        poke32(poke32(Bytes(one.begin(), one.end() - 4), rows_at, 65536), rows_at + 4, 65536));
    add(Channel::MpcTerrain, "truncated", Bytes(map.begin(), map.end() - 3));
    t = terrain(1002000, 12, 16);
    t.resolution = 1e-310;
    add(Channel::MpcTerrain, "resolution_denormal", encode(t));
    return files;
  }

 private:
  robot_state_t state(std::int64_t utime, bool contacts) const {
    robot_state_t m;
    msg::shape(m, nq_, nv_, contacts ? nc_ : 0);
    m.utime = utime;
    m.model_hash = hash_;
    m.session = kSession;
    for (int i = 0; i < nq_; ++i) m.q[i] = tidy(robot_.default_q[i]);
    for (auto& c : m.contact) c = 1;
    return m;
  }

  contact_plan_t plan(const std::vector<std::vector<std::int8_t>>& closed, bool cyclic) const {
    contact_plan_t m;
    m.utime = 1000000;
    m.cyclic = cyclic ? 1 : 0;
    for (const ContactSpec& c : robot_.contacts) m.contacts.push_back(c.frame);
    m.ncontacts = static_cast<std::int32_t>(m.contacts.size());
    m.nphases = static_cast<std::int32_t>(closed.size());
    m.closed = closed;
    m.duration.assign(closed.size(), 0.125);
    return m;
  }

  static command_t command(std::int64_t utime, const std::string& gait, double vx) {
    command_t m{};
    m.utime = utime;
    m.vx = vx;
    m.vy = 0.0;
    m.yaw_rate = 0.25;
    m.gait = gait;
    m.body_height = 0.0;
    return m;
  }

  // Holds the default posture: joint PD gains in K, no feed-forward.
  policy_t policy(std::int64_t utime, int knots, std::int64_t source) const {
    policy_t m;
    msg::shape(m, knots, nq_, nv_, nu_);
    m.utime = m.knot0_utime = utime;
    m.model_hash = hash_;
    m.source_id = source;
    m.session = kSession;
    m.tick = 1;
    m.t0 = 0.0;
    m.dt = 0.015625;
    m.phase = (1 << nc_) - 1;
    m.status = 0;
    for (int k = 0; k < knots; ++k) {
      for (int i = 0; i < nq_; ++i) m.x_ref[k][i] = tidy(robot_.default_q[i]);
      for (int j = 0; j < nu_; ++j) {
        m.K[k][j * 2 * nv_ + 6 + j] = 5.0;
        m.K[k][j * 2 * nv_ + nv_ + 6 + j] = 0.125;
      }
    }
    return m;
  }

  // Standing still, the feet alternating in pairs every 4 knots, each carrying a quarter of 25 N;
  // the two feet that lift at knot 4 land again 1/8 s later, one blind, one moved by the map.
  horizon_t horizon(std::int64_t utime, int knots) const {
    horizon_t m;
    msg::shape(m, knots, nq_, nc_, 2);
    for (int i = 0; i < 2; ++i) {
      m.foothold_contact[i] = 1 + i;
      m.foothold_time[i] = 0.125;
      m.foothold[i] = {0.25, i == 0 ? 0.125 : -0.125, 0.0078125 * i};
      m.foothold_source[i] = static_cast<std::int8_t>(i == 0 ? 1 : 3);
    }
    m.utime = utime;
    m.model_hash = hash_;
    for (int k = 0; k < knots; ++k) {
      m.t[k] = 0.015625 * k;
      for (int i = 0; i < nq_; ++i) m.q[k][i] = tidy(robot_.default_q[i]);
      m.contact_mask[k] = (k / 4) % 2 ? 0b1001 : 0b1111;
      m.impulse[k] = k == 4 ? 1 : 0;
      for (int c = 0; c < nc_; ++c) m.force[k][3 * c + 2] = 6.25;
    }
    return m;
  }

  // 1/64 m cells around the origin (exact in binary), a 6.25 cm box where x > 0.0625 m, a row of
  // unknown cells.
  static terrain_t terrain(std::int64_t utime, int rows, int cols) {
    terrain_t m;
    msg::shape(m, rows, cols);
    m.utime = utime;
    m.resolution = 0.015625;
    m.origin_x = -0.125;
    m.origin_y = -0.09375;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        m.height[r][c] = r == 2 ? std::numeric_limits<float>::quiet_NaN()
                                : (m.origin_x + c * m.resolution > 0.0625 ? 0.0625f : 0.0f);
    return m;
  }

  static mpc_status_t status(std::int64_t utime) {
    mpc_status_t m{};
    m.utime = utime;
    m.tick = 200;
    m.solve_ms = 1.5;
    m.prepare_ms = 0.75;
    m.prepared = 1;
    m.tick_ms = 2.25;
    m.iterations = 1;
    m.solver_status = 1;
    m.cost = 12.5;
    m.gap = 0.0078125;
    m.regularization = 1.0;
    m.step = 1.0;
    m.phase = 0b1001;
    m.plan_time = 1.0;
    m.policy_status = 0;
    m.source_id = 1;
    m.command[0] = 0.5;
    m.command[2] = 0.25;
    m.gait = "trot";
    m.commands_accepted = 100;
    return m;
  }

  const Robot& robot_;
  std::int64_t hash_;
  int nq_, nv_, nu_, nc_;
};

Bytes readFile(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int usage(const char* argv0, bool error) {
  std::fprintf(error ? stderr : stdout, "usage: %s [--check] DIR\n", argv0);
  return error ? 2 : 0;
}

}  // namespace
}  // namespace stride::fuzz

int main(int argc, char** argv) {
  using namespace stride::fuzz;
  namespace fs = std::filesystem;
  if (argc == 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0))
    return usage(argv[0], false);
  const bool check = argc == 3 && std::strcmp(argv[1], "--check") == 0;
  if (argc != 2 && !check) return usage(argv[0], true);
  const fs::path dir = argv[argc - 1];

  const stride::Robot robot =
      stride::loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  const std::map<std::string, Bytes> files = Corpus(robot).build();

  if (!check) {
    fs::create_directories(dir);
    for (const auto& [file, bytes] : files) {
      std::ofstream out(dir / file, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(bytes.data()),
                static_cast<std::streamsize>(bytes.size()));
      if (!out) {
        std::fprintf(stderr, "stride-fuzz-corpus: cannot write %s\n", (dir / file).c_str());
        return 1;
      }
    }
    std::printf("stride-fuzz-corpus: %zu files in %s\n", files.size(), dir.c_str());
    return 0;
  }

  int differ = 0;
  for (const auto& [file, bytes] : files) {
    const fs::path p = dir / file;
    if (!fs::is_regular_file(p)) {
      std::printf("missing: %s\n", file.c_str());
      ++differ;
    } else if (readFile(p) != bytes) {
      std::printf("differs: %s\n", file.c_str());
      ++differ;
    }
  }
  if (fs::is_directory(dir))
    for (const fs::directory_entry& e : fs::directory_iterator(dir))
      if (files.count(e.path().filename().string()) == 0) {
        std::printf("not written by stride-fuzz-corpus: %s\n", e.path().filename().c_str());
        ++differ;
      }
  if (differ > 0) {
    std::printf(
        "stride-fuzz-corpus: %s is not the current corpus (%d files); rewrite it with\n"
        "  rm -r %s && %s %s\n",
        dir.c_str(), differ, dir.c_str(), argv[0], dir.c_str());
    return 1;
  }
  std::printf("stride-fuzz-corpus: %s is current (%zu files)\n", dir.c_str(), files.size());
  return 0;
}
