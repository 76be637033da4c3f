#pragma once
// Checks on every message a Stride program receives, before and after decoding.
//
// lcm-gen's decoders trust the count fields of a message: a count of 2^31 makes them resize a
// vector to it (or throw), and a reused message object keeps stale data for a count of 0
// (LCM-NOTES.md). So the wire checks read the counts straight from the encoded bytes (big-endian,
// after the 8-byte type hash) and accept a buffer only when every count is the one the model
// expects and the buffer has exactly the size those counts imply; decoding such a buffer into an
// object that already has those sizes allocates nothing. The content checks then reject what a
// decoder cannot see: non-finite numbers, a quaternion that is not unit, inconsistent fields.

#include <cstdint>

#include "stride/command_t.hpp"
#include "stride/contact_plan_t.hpp"
#include "stride/horizon_t.hpp"
#include "stride/mpc_status_t.hpp"
#include "stride/policy_t.hpp"
#include "stride/robot_state_t.hpp"
#include "stride/terrain_t.hpp"

namespace stride::msg {

enum class Reject : std::uint8_t {
  None,
  Undecodable,        // too short, wrong type hash, or the decoder failed
  WrongSize,          // counts that do not match the model, or a size that does not match them
  NonFinite,          // NaN or infinity anywhere
  NotUnitQuaternion,  // base orientation with |q| far from 1
  BadField,           // e.g. dt <= 0, inconsistent derived sizes, flags outside {0, 1}
  OutOfOrder,         // stamp not newer than the last accepted one
  Stale,              // stamp older than the allowed age
  WrongModel,         // another robot's or model's message: model hash, nq or nv not ours
  Unauthenticated,    // with a key: unsigned, forged, replayed, stale or another key's
                      // (wire_auth.hpp)
  OtherSession,       // a state of another robot run while the one followed is alive
};
constexpr int kRejectReasons = static_cast<int>(Reject::OtherSession) + 1;
const char* describe(Reject reason);

// Quaternions within this distance of unit norm are accepted (and renormalized by the reader);
// an estimator's float rounding stays orders of magnitude below it.
constexpr double kQuaternionTolerance = 1e-4;

// The model a receiver runs, as the wire carries it (robot_model_t): what a state or policy must
// claim to be accepted.
struct WireModel {
  std::int64_t hash = 0;  // config/model_hash.hpp
  int nq = 0, nv = 0, nu = 0;
  const char* robot = "";  // for messages only
};
// What a received state or policy claims to be, read from its raw bytes (no decode).
struct WireClaim {
  std::int64_t hash = 0;
  int nq = 0, nv = 0;
  bool operator==(const WireClaim& o) const { return hash == o.hash && nq == o.nq && nv == o.nv; }
};
bool readStateClaim(const void* buf, int size, WireClaim& claim);
bool readPolicyClaim(const void* buf, int size, WireClaim& claim);
// The controller a policy comes from (policy_t.source_id), read from its raw bytes; false when
// the buffer is too short or not a policy_t (its type fingerprint).
bool readPolicySource(const void* buf, int size, std::int64_t& source_id);
// The robot run a state comes from (robot_state_t.session) and the one a policy answers
// (policy_t.session), read from the raw bytes; false when the buffer is too short.
bool readStateSession(const void* buf, int size, std::int64_t& session);
bool readPolicySession(const void* buf, int size, std::int64_t& session);
// "expected nq 19, nv 18 (anymal_c, hash 8c1d...), got nq 29, nv 28 (hash 03a4...)", or for the
// same sizes "expected hash 8c1d... (anymal_c, nq 19, nv 18), got hash 5e7f...: same sizes, another
// joint layout". Into a caller's buffer (no allocation); returns `out`.
const char* describeMismatch(const WireModel& expected, const WireClaim& got, char* out, int n);
// A hash as the programs print it: 16 hex digits.
void formatHash(std::int64_t hash, char out[17]);

// Size and model checks on encoded bytes, before decode(): WrongModel when the hash, nq or nv is
// not the model's, WrongSize when the buffer does not match its own counts. max_contacts bounds
// the optional flags.
Reject checkStateWire(const void* buf, int size, const WireModel& model, int max_contacts);
Reject checkPolicyWire(const void* buf, int size, const WireModel& model, int max_knots);
Reject checkPlanWire(const void* buf, int size, int max_contacts, int max_phases);
// A command whose gait name has at most kMaxGaitName characters.
constexpr int kMaxGaitName = 31;
Reject checkCommandWire(const void* buf, int size);
// A status whose three strings (wrong_model_cause, gait, jump_refusal) have lengths inside the
// buffer, each NUL-terminated, and the exact size they imply. It has no counts: this is all that
// keeps lcm-gen's decoder from reading past the buffer.
Reject checkStatusWire(const void* buf, int size);
// An elevation map: terrain_t's type fingerprint (a map is 40 kB of floats: another type's bytes
// must not pass for one), rows and cols >= 1 with rows * cols <= max_cells (compared without
// overflow), and the exact size they imply.
Reject checkTerrainWire(const void* buf, int size, int max_cells);

// Content checks on decoded messages. floating_base: q[3..7) is a quaternion (x y z w).
Reject checkState(const robot_state_t& m, bool floating_base);
Reject checkPolicy(const policy_t& m, bool floating_base);
// Durations > 0, flags in {0, 1}, a stamp >= 0.
Reject checkPlan(const contact_plan_t& m);
// Finite numbers, a stamp >= 0. The gait name and the limits are the receiver's (its robot's gaits,
// its configuration's limits).
Reject checkCommand(const command_t& m);
// Finite origin, a resolution within [kMinTerrainResolution, kMaxTerrainResolution], a stamp >= 0,
// the arrays of the counts' sizes; heights NaN (unknown cells) or finite, never infinite.
constexpr double kMinTerrainResolution = 1e-4, kMaxTerrainResolution = 100.0;  // [m]
Reject checkTerrain(const terrain_t& m);

// The encoded size of a state / policy / map with these dimensions (hash included): what a
// publisher preallocates its buffer for.
int stateWireSize(int nq, int nv, int ncontacts);
int policyWireSize(int knots, int nq, int nv, int nu);
long terrainWireSize(int rows, int cols);

// Decodes a buffer that passed checkStateWire, and trims the arrays to their counts: lcm-gen's
// decoder skips an array whose count is 0, which would leave a reused object's old entries.
bool decode(const void* buf, int size, robot_state_t& m);

// The wire's contact masks (policy_t.phase, mpc_status_t.phase, horizon_t.contact_mask) are int32
// with bit c for contact c: at most this many contacts fit (the sign bit left alone). The contact
// limit (solver/contact/contact_set.hpp, kMaxContacts) must stay within it: static_assert where
// both meet (controller/policy_writer.cpp).
constexpr int kContactMaskBits = 31;

// horizon_t's footholds (issue 31): at most this many per contact (nfootholds <= it times
// ncontacts), each foothold_source in [0, kFootholdSources) (GaitGenerator's StanceSource:
// measured, blind, nominal, moved, unreachable, unknown).
constexpr int kHorizonFootholdsPerContact = 4;
constexpr int kFootholdSources = 6;

// Resizes a message's arrays to these dimensions (sets the count fields too). Done once at setup,
// so that later decodes and encodes of the same dimensions allocate nothing.
void shape(robot_state_t& m, int nq, int nv, int ncontacts);
void shape(policy_t& m, int knots, int nq, int nv, int nu);
// footholds: the footholds' capacity (nfootholds is set to it, every entry 0); a writer that fills
// fewer lowers nfootholds, which needs no allocation, nor does raising it back to the capacity.
void shape(horizon_t& m, int knots, int nq, int ncontacts, int footholds = 0);
void shape(terrain_t& m, int rows, int cols);  // every height NaN (unknown)

}  // namespace stride::msg
