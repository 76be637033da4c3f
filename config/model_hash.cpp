#include "config/model_hash.hpp"

#include <cmath>
#include <cstdio>
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

// A placement as text, rounded: translation to the millimetre, rotation (and axis) entries to
// 1e-3, so that the same geometry from two parsers, compilers or instruction sets hashes alike
// (the last bits of cos and sin of a URDF's rpy differ between them; a value within a few ulp of
// a rounding boundary, as 0.0005 m exactly, is the one case that could still differ). "-0" is "0".
void fnv1aRounded(std::uint64_t& h, const double* x, int n, double unit) {
  std::string text;
  char buf[32];
  for (int i = 0; i < n; ++i) {
    const long long r = std::llround(x[i] / unit);
    std::snprintf(buf, sizeof buf, "%lld,", r);
    text += buf;
  }
  fnv1a(h, text);
}

void fnv1aPlacement(std::uint64_t& h, const SE3& m) {
  fnv1aRounded(h, m.p.data(), 3, 1e-3);
  fnv1aRounded(h, m.R.data(), 9, 1e-3);
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
  const Model& model = robot.model;
  for (const WireJoint& j : wireJoints(model)) {
    fnv1a(h, j.name);
    fnv1a(h, j.type);
  }
  // The kinematic tree's geometry (issue 34: ANYmal B and C share every joint name): each joint's
  // parent, placement and axis. Not masses, inertias or limits.
  fnv1a(h, "geometry");
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    fnv1a(h, std::to_string(j.parent));
    fnv1aPlacement(h, j.placement);
    fnv1aRounded(h, j.axis.data(), 3, 1e-3);
  }
  fnv1a(h, "contacts");
  for (const ContactSpec& c : robot.contacts) {
    fnv1a(h, c.frame);
    for (const Frame& f : model.frames)  // the first of that name, as Model::getFrameId
      if (f.name == c.frame) {
        fnv1a(h, std::to_string(f.parentJoint));
        fnv1aPlacement(h, f.placement);
        break;
      }
  }
  std::int64_t out;
  std::memcpy(&out, &h, 8);
  return out;
}

}  // namespace stride
