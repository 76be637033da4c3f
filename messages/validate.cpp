#include "messages/validate.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "messages/wire_reader.hpp"

namespace stride::msg {

const char* describe(Reject reason) {
  switch (reason) {
    case Reject::None:
      return "ok";
    case Reject::Undecodable:
      return "undecodable (truncated, wrong type or corrupt)";
    case Reject::WrongSize:
      return "sizes do not match the model";
    case Reject::NonFinite:
      return "non-finite value";
    case Reject::NotUnitQuaternion:
      return "base quaternion not unit";
    case Reject::BadField:
      return "inconsistent field";
    case Reject::OutOfOrder:
      return "stamp not newer than the last accepted";
    case Reject::Stale:
      return "stamp older than the allowed age";
    case Reject::WrongModel:
      return "another robot's model (hash or sizes)";
    case Reject::Unauthenticated:
      return "not signed with our key (unsigned, forged, replayed, stale or another key's)";
    case Reject::OtherSession:
      return "another run of the robot (session) than the one followed";
  }
  return "unknown";
}

namespace {

constexpr int kHash = 8;  // every LCM message starts with its 64-bit type fingerprint

// Big-endian reads at fixed offsets: readInt32, readInt64 (wire_reader.hpp, the one reader).

// Offsets after the type hash: robot_state_t is utime, model_hash, session, nq, nv, ...; policy_t
// is utime, model_hash, source_id, session, knot0_utime, tick, t0, dt, then knots nq nv nu nx ndx
// nk.
constexpr long kStateHashAt = kHash + 8, kStateSessionAt = kHash + 16, kStateNqAt = kHash + 24;
constexpr long kPolicyHashAt = kHash + 8, kPolicySourceAt = kHash + 16,
               kPolicySessionAt = kHash + 24, kPolicyCountsAt = kHash + 64;
// terrain_t is utime, origin_x, origin_y, resolution, then rows and cols.
constexpr long kTerrainRowsAt = kHash + 32, kTerrainHeader = kTerrainRowsAt + 8;

template <typename Vec>
bool allFinite(const Vec& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

Reject checkQuaternion(const std::vector<double>& q) {
  const double n = std::sqrt(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]);
  return std::abs(n - 1.0) <= kQuaternionTolerance ? Reject::None : Reject::NotUnitQuaternion;
}

}  // namespace

int stateWireSize(int nq, int nv, int ncontacts) {
  return kHash + 8 + 8 + 8 + 4 + 4 + 8 * (nq + nv) + 4 + ncontacts;
}

int policyWireSize(int knots, int nq, int nv, int nu) {
  const long per_knot = 8L * ((nq + nv) + nu + static_cast<long>(nu) * 2 * nv);
  return static_cast<int>(kHash + 8 * 8 + 7 * 4 + knots * per_knot + 4 + 1);
}

long terrainWireSize(int rows, int cols) {
  return kTerrainHeader + 4L * rows * cols;
}

bool readStateClaim(const void* buf, int size, WireClaim& claim) {
  std::int32_t nq, nv;
  if (!readInt64(buf, size, kStateHashAt, claim.hash) || !readInt32(buf, size, kStateNqAt, nq) ||
      !readInt32(buf, size, kStateNqAt + 4, nv))
    return false;
  claim.nq = nq;
  claim.nv = nv;
  return true;
}

bool readPolicySource(const void* buf, int size, std::int64_t& source_id) {
  std::int64_t type = 0;  // another type on the channel (garbage, say) is nobody's policy
  return readInt64(buf, size, 0, type) && type == policy_t::getHash() &&
         readInt64(buf, size, kPolicySourceAt, source_id);
}

bool readStateSession(const void* buf, int size, std::int64_t& session) {
  return readInt64(buf, size, kStateSessionAt, session);
}

bool readPolicySession(const void* buf, int size, std::int64_t& session) {
  return readInt64(buf, size, kPolicySessionAt, session);
}

bool readPolicyClaim(const void* buf, int size, WireClaim& claim) {
  std::int32_t nq, nv;
  if (!readInt64(buf, size, kPolicyHashAt, claim.hash) ||
      !readInt32(buf, size, kPolicyCountsAt + 4, nq) ||
      !readInt32(buf, size, kPolicyCountsAt + 8, nv))
    return false;
  claim.nq = nq;
  claim.nv = nv;
  return true;
}

void formatHash(std::int64_t hash, char out[17]) {
  std::uint64_t u;
  std::memcpy(&u, &hash, 8);
  std::snprintf(out, 17, "%016llx", static_cast<unsigned long long>(u));
}

const char* describeMismatch(const WireModel& expected, const WireClaim& got, char* out, int n) {
  char ours[17], theirs[17];
  formatHash(expected.hash, ours);
  formatHash(got.hash, theirs);
  if (got.nq != expected.nq || got.nv != expected.nv)
    std::snprintf(out, n, "expected nq %d, nv %d (%s, hash %s), got nq %d, nv %d (hash %s)",
                  expected.nq, expected.nv, expected.robot, ours, got.nq, got.nv, theirs);
  else
    std::snprintf(out, n,
                  "expected hash %s (%s, nq %d, nv %d), got hash %s: the same sizes, another "
                  "robot or joint order (compare stride-mpc --print-model)",
                  ours, expected.robot, expected.nq, expected.nv, theirs);
  return out;
}

Reject checkStateWire(const void* buf, int size, const WireModel& model, int max_contacts) {
  WireClaim claim;
  std::int32_t nc;
  if (!readStateClaim(buf, size, claim)) return Reject::Undecodable;
  if (claim.hash != model.hash || claim.nq != model.nq || claim.nv != model.nv)
    return Reject::WrongModel;
  if (!readInt32(buf, size, kStateNqAt + 8 + 8L * (model.nq + model.nv), nc))
    return Reject::Undecodable;
  if (nc < 0 || nc > max_contacts) return Reject::WrongSize;
  return size == stateWireSize(model.nq, model.nv, nc) ? Reject::None : Reject::WrongSize;
}

Reject checkPolicyWire(const void* buf, int size, const WireModel& model, int max_knots) {
  WireClaim claim;
  if (!readPolicyClaim(buf, size, claim)) return Reject::Undecodable;
  if (claim.hash != model.hash || claim.nq != model.nq || claim.nv != model.nv)
    return Reject::WrongModel;
  std::int32_t f[7];  // knots nq nv nu nx ndx nk
  for (int i = 0; i < 7; ++i)
    if (!readInt32(buf, size, kPolicyCountsAt + 4 * i, f[i])) return Reject::Undecodable;
  const int nq = model.nq, nv = model.nv, nu = model.nu;
  if (f[0] < 1 || f[0] > max_knots || f[3] != nu || f[4] != nq + nv || f[5] != 2 * nv ||
      f[6] != nu * 2 * nv)
    return Reject::WrongSize;
  return size == policyWireSize(f[0], nq, nv, nu) ? Reject::None : Reject::WrongSize;
}

Reject checkPlanWire(const void* buf, int size, int max_contacts, int max_phases) {
  long at = kHash + 8 + 1;
  std::int32_t nc, np, len;
  if (!readInt32(buf, size, at, nc)) return Reject::Undecodable;
  if (nc < 1 || nc > max_contacts) return Reject::WrongSize;
  at += 4;
  for (int c = 0; c < nc; ++c) {
    if (!readInt32(buf, size, at, len)) return Reject::Undecodable;
    if (len < 1 || len > 256 || at + 4 + len > size) return Reject::WrongSize;
    at += 4 + len;
  }
  if (!readInt32(buf, size, at, np)) return Reject::Undecodable;
  if (np < 1 || np > max_phases) return Reject::WrongSize;
  at += 4 + 8L * np + static_cast<long>(np) * nc;
  return at == size ? Reject::None : Reject::WrongSize;
}

Reject checkCommandWire(const void* buf, int size) {
  std::int32_t len;  // the string's length field counts its terminating NUL
  if (!readInt32(buf, size, kHash + 32, len)) return Reject::Undecodable;
  if (len < 1 || len > kMaxGaitName + 1) return Reject::WrongSize;
  // utime, vx, vy, yaw_rate; gait; body_height, jump_id, jump[4].
  return size == kHash + 32 + 4 + len + 8 + 4 + 32 ? Reject::None : Reject::WrongSize;
}

Reject checkStatusWire(const void* buf, int size) {
  // mpc_status_t.lcm: the fixed fields before wrong_model_cause (type hash included), between it
  // and gait, between gait and jump_refusal, and after that. lcm-gen's decoder takes a string's
  // length minus one as the number of characters to copy: a length of -2^31 overflows (undefined
  // behaviour, in practice 2^31 - 1 characters read past the buffer) and 0 makes std::string
  // throw.
  constexpr long kBeforeCause = kHash + 158, kBetween = 48, kAfterGait = 37, kAfterRefusal = 41;
  long at = kBeforeCause;
  for (const long fixed_after : {kBetween, kAfterGait, kAfterRefusal}) {
    std::int32_t len;  // counts the terminating NUL, which must be there
    if (!readInt32(buf, size, at, len)) return Reject::Undecodable;
    if (len < 1 || len > size - at - 4) return Reject::WrongSize;
    if (static_cast<const unsigned char*>(buf)[at + 4 + len - 1] != 0) return Reject::Undecodable;
    at += 4 + len + fixed_after;
  }
  return at == size ? Reject::None : Reject::WrongSize;
}

Reject checkTerrainWire(const void* buf, int size, int max_cells) {
  std::int64_t type = 0;
  std::int32_t rows, cols;
  if (!readInt64(buf, size, 0, type) || type != terrain_t::getHash()) return Reject::Undecodable;
  if (!readInt32(buf, size, kTerrainRowsAt, rows) ||
      !readInt32(buf, size, kTerrainRowsAt + 4, cols))
    return Reject::Undecodable;
  // Divided, not multiplied: rows * cols of two counts near 2^31 overflows int.
  if (rows < 1 || cols < 1 || rows > max_cells / cols) return Reject::WrongSize;
  return size == terrainWireSize(rows, cols) ? Reject::None : Reject::WrongSize;
}

Reject checkState(const robot_state_t& m, bool floating_base) {
  if (m.nq != static_cast<int>(m.q.size()) || m.nv != static_cast<int>(m.v.size()) ||
      m.ncontacts != static_cast<int>(m.contact.size()))
    return Reject::WrongSize;
  if (!allFinite(m.q) || !allFinite(m.v)) return Reject::NonFinite;
  for (std::int8_t c : m.contact)
    if (c != 0 && c != 1) return Reject::BadField;
  if (m.utime < 0) return Reject::BadField;
  return floating_base ? checkQuaternion(m.q) : Reject::None;
}

Reject checkPolicy(const policy_t& m, bool floating_base) {
  if (m.knots < 1 || static_cast<int>(m.x_ref.size()) != m.knots ||
      static_cast<int>(m.u_ff.size()) != m.knots || static_cast<int>(m.K.size()) != m.knots)
    return Reject::WrongSize;
  if (!std::isfinite(m.dt) || m.dt <= 0.0 || !std::isfinite(m.t0)) return Reject::BadField;
  for (int k = 0; k < m.knots; ++k) {
    if (static_cast<int>(m.x_ref[k].size()) != m.nx || static_cast<int>(m.u_ff[k].size()) != m.nu ||
        static_cast<int>(m.K[k].size()) != m.nk)
      return Reject::WrongSize;
    if (!allFinite(m.x_ref[k]) || !allFinite(m.u_ff[k]) || !allFinite(m.K[k]))
      return Reject::NonFinite;
    if (floating_base && checkQuaternion(m.x_ref[k]) != Reject::None)
      return Reject::NotUnitQuaternion;
  }
  return m.status >= 0 && m.status <= 3 ? Reject::None : Reject::BadField;
}

Reject checkPlan(const contact_plan_t& m) {
  if (m.ncontacts != static_cast<int>(m.contacts.size()) ||
      m.nphases != static_cast<int>(m.duration.size()) ||
      m.nphases != static_cast<int>(m.closed.size()))
    return Reject::WrongSize;
  for (int i = 0; i < m.nphases; ++i) {
    if (!std::isfinite(m.duration[i]) || m.duration[i] <= 0.0) return Reject::BadField;
    if (static_cast<int>(m.closed[i].size()) != m.ncontacts) return Reject::WrongSize;
    for (std::int8_t c : m.closed[i])
      if (c != 0 && c != 1) return Reject::BadField;
  }
  if (m.utime < 0) return Reject::BadField;  // as every stamp (and a tick subtracts it)
  return m.cyclic == 0 || m.cyclic == 1 ? Reject::None : Reject::BadField;
}

Reject checkCommand(const command_t& m) {
  for (double x :
       {m.vx, m.vy, m.yaw_rate, m.body_height, m.jump[0], m.jump[1], m.jump[2], m.jump[3]})
    if (!std::isfinite(x)) return Reject::NonFinite;
  return m.utime >= 0 && m.jump_id >= 0 ? Reject::None : Reject::BadField;
}

Reject checkTerrain(const terrain_t& m) {
  if (m.rows < 1 || m.cols < 1 || static_cast<int>(m.height.size()) != m.rows)
    return Reject::WrongSize;
  for (const std::vector<float>& row : m.height) {
    if (static_cast<int>(row.size()) != m.cols) return Reject::WrongSize;
    for (float h : row)
      if (std::isinf(h)) return Reject::NonFinite;  // NaN is an unknown cell, infinity nothing
  }
  if (!std::isfinite(m.origin_x) || !std::isfinite(m.origin_y)) return Reject::NonFinite;
  // A cell between 0.1 mm and 100 m: finer or coarser is no map (and grid coordinates from a
  // denormal resolution would overflow).
  if (!(m.resolution >= kMinTerrainResolution && m.resolution <= kMaxTerrainResolution))
    return Reject::BadField;
  return m.utime >= 0 ? Reject::None : Reject::BadField;
}

bool decode(const void* buf, int size, robot_state_t& m) {
  if (m.decode(buf, 0, size) < 0) return false;
  // Shrinking, or growing within the capacity shape() reserved: no allocation.
  m.q.resize(m.nq);
  m.v.resize(m.nv);
  m.contact.resize(m.ncontacts);
  return true;
}

void shape(robot_state_t& m, int nq, int nv, int ncontacts) {
  m.session = 0;  // no robot run yet (lcm-gen leaves the fields unset)
  m.nq = nq;
  m.nv = nv;
  m.ncontacts = ncontacts;
  m.q.assign(nq, 0.0);
  m.v.assign(nv, 0.0);
  m.contact.assign(ncontacts, 0);
}

void shape(policy_t& m, int knots, int nq, int nv, int nu) {
  m.session = 0;  // answers no robot run yet
  m.knots = knots;
  m.nq = nq;
  m.nv = nv;
  m.nu = nu;
  m.nx = nq + nv;
  m.ndx = 2 * nv;
  m.nk = nu * 2 * nv;
  m.x_ref.assign(knots, std::vector<double>(m.nx, 0.0));
  m.u_ff.assign(knots, std::vector<double>(nu, 0.0));
  m.K.assign(knots, std::vector<double>(m.nk, 0.0));
}

void shape(horizon_t& m, int knots, int nq, int ncontacts, int footholds) {
  m.knots = knots;
  m.nq = nq;
  m.ncontacts = ncontacts;
  m.nf = 3 * ncontacts;
  m.t.assign(knots, 0.0);
  m.q.assign(knots, std::vector<double>(nq, 0.0));
  m.contact_mask.assign(knots, 0);
  m.impulse.assign(knots, 0);
  m.force.assign(knots, std::vector<double>(m.nf, 0.0));
  m.nfootholds = footholds;
  m.foothold_contact.assign(footholds, 0);
  m.foothold_time.assign(footholds, 0.0);
  m.foothold.assign(footholds, std::vector<double>(3, 0.0));
  m.foothold_source.assign(footholds, 0);
}

void shape(terrain_t& m, int rows, int cols) {
  m.rows = rows;
  m.cols = cols;
  m.height.assign(rows, std::vector<float>(cols, std::numeric_limits<float>::quiet_NaN()));
}

}  // namespace stride::msg
