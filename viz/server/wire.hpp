#pragma once
// Checks and decodes of the messages stride-viz reads that messages/validate.hpp does not cover:
// robot_model_t, horizon_t, mpc_status_t. The same rules (validate.hpp): lcm-gen's decoders
// trust the counts of a message, so every count is read from the encoded bytes and checked
// before decode() sizes anything with it; then the decoded content is checked. A rejected
// message changes nothing the caller holds (decoding goes into the caller's scratch message).

#include "messages/validate.hpp"
#include "stride/horizon_t.hpp"
#include "stride/mpc_status_t.hpp"
#include "stride/robot_model_t.hpp"

namespace stride::viz {

// robot_model_t: strings and counts walked on the bytes (every string non-empty and
// NUL-terminated, counts within the buffer, the exact size), then decoded; joint types known,
// first indices inside nq / nv, nu <= nv.
msg::Reject decodeModel(const void* buf, int size, robot_model_t& m);

// horizon_t of `model` (hash, nq) with `ncontacts` contact frames: the counts on the bytes
// (1 <= knots <= max_knots, nq, ncontacts and nf = 3 ncontacts the model's, 0 <= nfootholds <=
// msg::kHorizonFootholdsPerContact ncontacts), the exact size they imply, then the content: finite
// numbers, unit base quaternions (floating_base), masks of existing contacts; footholds of existing
// contacts, after the state (time > 0), of a known source (< msg::kFootholdSources).
msg::Reject decodeHorizon(const void* buf, int size, const msg::WireModel& model, int ncontacts,
                          int max_knots, bool floating_base, horizon_t& m);

// mpc_status_t has no counts, only two strings: their lengths checked on the bytes
// (msg::checkStatusWire: inside the buffer, at least 1, NUL-terminated, the exact size), then
// decoded; the stamp must be >= 0. Its numbers may be NaN (a failed solve's cost): the frames carry
// them as null.
msg::Reject decodeStatus(const void* buf, int size, mpc_status_t& m);

}  // namespace stride::viz
