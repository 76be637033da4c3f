#include "viz/server/wire.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <string>

#include "messages/wire_reader.hpp"

namespace stride::viz {

namespace {

constexpr int kTypeHash = 8;  // every LCM message starts with its 64-bit type fingerprint

bool finite(const std::vector<double>& x) {
  for (double d : x)
    if (!std::isfinite(d)) return false;
  return true;
}

// lcm-gen's decoders throw on a string length below 1 (they construct a string of size_t(-1)
// characters, which std::string refuses) and may throw std::bad_alloc: a viewer drops the message
// rather than die.
template <typename Message>
bool decodeExactly(const void* buf, int size, Message& m) {
  try {
    return m.decode(buf, 0, size) == size;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

msg::Reject decodeModel(const void* buf, int size, robot_model_t& m) {
  msg::WireReader w(buf, size);
  std::int32_t dims[3], njoints, ncontacts;
  if (!w.skip(kTypeHash) || !w.string() || !w.skip(8)) return msg::Reject::Undecodable;
  for (std::int32_t& d : dims)
    if (!w.int32(d)) return msg::Reject::Undecodable;
  // A joint takes at least two 1-character strings and two indices: 4 + 2 + 4 + 2 + 4 + 4 bytes.
  if (!w.count(njoints, 20)) return msg::Reject::WrongSize;
  for (int i = 0; i < 2 * njoints; ++i)
    if (!w.string()) return msg::Reject::Undecodable;
  if (!w.skip(8L * njoints) || !w.count(ncontacts, 6)) return msg::Reject::WrongSize;
  for (int i = 0; i < ncontacts; ++i)
    if (!w.string()) return msg::Reject::Undecodable;
  if (w.at() != size) return msg::Reject::WrongSize;
  if (!decodeExactly(buf, size, m)) return msg::Reject::Undecodable;

  if (m.nq < 0 || m.nv < 0 || m.nu < 0 || m.nu > m.nv || m.robot.empty())
    return msg::Reject::BadField;
  for (int j = 0; j < m.njoints; ++j) {
    const std::string& type = m.joint_types[j];
    const int nq = type == "free-flyer" ? 7 : 1, nv = type == "free-flyer" ? 6 : 1;
    if (type != "free-flyer" && type != "revolute" && type != "prismatic")
      return msg::Reject::BadField;
    if (m.joint_idx_q[j] < 0 || m.joint_idx_q[j] + nq > m.nq || m.joint_idx_v[j] < 0 ||
        m.joint_idx_v[j] + nv > m.nv)
      return msg::Reject::BadField;
  }
  return msg::Reject::None;
}

msg::Reject decodeHorizon(const void* buf, int size, const msg::WireModel& model, int ncontacts,
                          int max_knots, bool floating_base, horizon_t& m) {
  // utime, model_hash, then the four counts.
  msg::WireReader w(buf, size);
  std::int64_t hash;
  std::int32_t knots, nq, nc, nf;
  if (!w.skip(kTypeHash + 8) || !w.int64(hash) || !w.int32(knots) || !w.int32(nq) || !w.int32(nc) ||
      !w.int32(nf))
    return msg::Reject::Undecodable;
  if (hash != model.hash || nq != model.nq) return msg::Reject::WrongModel;
  if (knots < 1 || knots > max_knots || nc != ncontacts || nf != 3 * ncontacts)
    return msg::Reject::WrongSize;
  // The size those counts imply, from lcm-gen's own size function (it reads the counts only), so
  // a field added per knot is accounted for without a change here. The footholds' count follows
  // the knots' arrays: where it sits, from the size of the message without footholds.
  horizon_t shape;
  shape.knots = knots;
  shape.nq = nq;
  shape.ncontacts = nc;
  shape.nf = nf;
  shape.nfootholds = 0;
  std::int32_t nfootholds;
  if (!w.skip(shape.getEncodedSize() - 4 - w.at()) || !w.int32(nfootholds))
    return msg::Reject::WrongSize;
  if (nfootholds < 0 || nfootholds > msg::kHorizonFootholdsPerContact * ncontacts)
    return msg::Reject::WrongSize;
  shape.nfootholds = nfootholds;
  if (size != shape.getEncodedSize()) return msg::Reject::WrongSize;
  if (!decodeExactly(buf, size, m)) return msg::Reject::Undecodable;

  if (!finite(m.t) || m.utime < 0) return msg::Reject::NonFinite;
  const std::int32_t all = ncontacts >= 31 ? -1 : (std::int32_t{1} << ncontacts) - 1;
  for (int k = 0; k < m.knots; ++k) {
    if (!finite(m.q[k]) || !finite(m.force[k])) return msg::Reject::NonFinite;
    if ((m.contact_mask[k] & ~all) != 0) return msg::Reject::BadField;
    if (floating_base) {
      const std::vector<double>& q = m.q[k];
      const double n = std::sqrt(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]);
      if (std::abs(n - 1.0) > msg::kQuaternionTolerance) return msg::Reject::NotUnitQuaternion;
    }
  }
  // Each foothold: finite, after the state, of an existing contact, from a known source. (Only the
  // first nfootholds entries: a count of 0 leaves a reused message's old ones, which lcm-gen's
  // decoder skips.)
  for (int i = 0; i < m.nfootholds; ++i) {
    const std::vector<double>& p = m.foothold[i];
    if (!std::isfinite(m.foothold_time[i]) || !std::isfinite(p[0]) || !std::isfinite(p[1]) ||
        !std::isfinite(p[2]))
      return msg::Reject::NonFinite;
    if (m.foothold_time[i] <= 0.0 || m.foothold_contact[i] < 0 ||
        m.foothold_contact[i] >= ncontacts || m.foothold_source[i] < 0 ||
        m.foothold_source[i] >= msg::kFootholdSources)
      return msg::Reject::BadField;
  }
  return msg::Reject::None;
}

msg::Reject decodeStatus(const void* buf, int size, mpc_status_t& m) {
  // Its string lengths on the bytes first: lcm-gen's decoder only checks that a length is not past
  // the end, and reads ~2 GB past the buffer for a length of -2^31.
  if (const msg::Reject r = msg::checkStatusWire(buf, size); r != msg::Reject::None) return r;
  if (!decodeExactly(buf, size, m)) return msg::Reject::Undecodable;
  return m.utime >= 0 ? msg::Reject::None : msg::Reject::BadField;
}

}  // namespace stride::viz
