#include "config/model_hash.hpp"

#include <cstring>

namespace stride {

namespace {
// FNV-1a, 64-bit (offset basis and prime from the published definition).
void fnv1a(std::uint64_t& h, const std::string& s) {
  for (const char c : s) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  h *= 1099511628211ULL;  // the terminating NUL: h ^= 0 leaves h, the multiplication remains
}
}  // namespace

std::vector<WireJoint> wireJoints(const Model& model) {
  std::vector<WireJoint> joints;
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    // toString's names (free-flyer, revolute, prismatic) are the wire's joint types and enter the
    // hash: renaming one changes every model hash.
    joints.push_back({j.name, toString(j.type), j.idx_q, j.idx_v});
  }
  return joints;
}

std::int64_t modelHash(const Robot& robot) {
  std::uint64_t h = 14695981039346656037ULL;
  for (const WireJoint& j : wireJoints(robot.model)) {
    fnv1a(h, j.name);
    fnv1a(h, j.type);
  }
  fnv1a(h, "contacts");
  for (const ContactSpec& c : robot.contacts) fnv1a(h, c.frame);
  std::int64_t out;
  std::memcpy(&out, &h, 8);
  return out;
}

}  // namespace stride
