#include "config/robot_config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "config/package_path.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/srdf.hpp"

namespace stride {

namespace {
[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw ConfigError("robot config '" + path + "': " + what);
}

YAML::Node need(const YAML::Node& parent, const char* key, const std::string& path) {
  const YAML::Node n = parent[key];
  if (!n) fail(path, std::string("missing key '") + key + "'");
  return n;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// A misspelt optional key would otherwise be ignored silently, and its default used instead.
// `where` prefixes the key in the message ("contacts[1].", "default_posture.").
void checkKeys(const YAML::Node& map, const std::vector<std::string>& known,
               const std::string& path, const std::string& where) {
  if (!map.IsMap())
    fail(path, (where.empty() ? "the top level" : "'" + where.substr(0, where.size() - 1) + "'") +
                   " must be a mapping");
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(known.begin(), known.end(), key) == known.end())
      fail(path, "unknown key '" + where + key + "' (known: " + joined(known) + ")");
  }
}

bool actuated(const Joint& j) {
  return j.type != JointType::Universe && j.type != JointType::FreeFlyer;
}

// A joint named in the YAML: it exists and is actuated (the free-flyer is set by `base`).
const Joint& namedJoint(const Model& model, const std::string& name, const std::string& path,
                        const std::string& key) {
  if (!model.existJoint(name)) fail(path, key + ": joint '" + name + "' is not in the URDF");
  const Joint& j = model.joints[model.getJointId(name)];
  if (!actuated(j)) fail(path, key + ": joint '" + name + "' is the free-flyer base, not actuated");
  return j;
}

std::vector<ContactSpec> readContacts(const YAML::Node& contacts, const Model& model,
                                      const std::string& path) {
  if (!contacts.IsSequence()) fail(path, "contacts must be a list of {frame, dim}");
  std::vector<ContactSpec> out;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const YAML::Node c = contacts[i];
    checkKeys(c, {"frame", "dim"}, path, "contacts[" + std::to_string(i) + "].");
    ContactSpec spec{need(c, "frame", path).as<std::string>(), need(c, "dim", path).as<int>()};
    if (!model.existFrame(spec.frame))
      fail(path, "contact frame '" + spec.frame + "' is not in the URDF");
    // A moving joint's frame sits on the joint's axis (a knee, an ankle), not under the foot: the
    // controller would plan forces at the joint (issue 34). The frames of the bodies it moves are
    // what was meant.
    if (const Frame& f = model.frames[model.getFrameId(spec.frame)]; f.type == FrameType::Joint) {
      std::vector<std::string> bodies;
      for (const Frame& g : model.frames)
        if (g.parentJoint == f.parentJoint && g.type != FrameType::Joint) bodies.push_back(g.name);
      fail(path,
           "contacts[" + std::to_string(i) + "].frame: '" + spec.frame +
               "' is a joint (its frame is on the joint's axis, not at the foot); name the "
               "foot's link or frame instead" +
               (bodies.empty() ? "" : " (the frames this joint moves: " + joined(bodies) + ")"));
    }
    if (spec.dim != 3 && spec.dim != 6)
      fail(path, "contact '" + spec.frame + "' has dim " + std::to_string(spec.dim) + " (3 or 6)");
    for (const auto& other : out)
      if (other.frame == spec.frame)
        fail(path, "contact frame '" + spec.frame + "' is listed twice");
    out.push_back(spec);
  }
  return out;
}

void checkLimit(double limit, const std::string& joint, const std::string& path) {
  if (!(limit > 0) || !std::isfinite(limit))
    fail(path, "torque limit of '" + joint + "' must be positive and finite");
}

// `torque_limits:` absent (URDF efforts), one number (every joint) or a map joint -> limit (the
// others keep their URDF effort). A joint left with no finite limit would make the box-constrained
// solver and the mock robot unbounded: an error, not a silent infinity.
void applyTorqueLimits(const YAML::Node& limits, Model& model, const std::string& path) {
  if (limits && limits.IsScalar()) {
    const double limit = limits.as<double>();
    checkLimit(limit, "every joint", path);
    for (const Joint& j : model.joints)
      if (actuated(j)) model.effortLimit[j.idx_v] = limit;
  } else if (limits && limits.IsMap()) {
    for (const auto& kv : limits) {
      const Joint& j = namedJoint(model, kv.first.as<std::string>(), path, "torque_limits");
      const double limit = kv.second.as<double>();
      checkLimit(limit, j.name, path);
      model.effortLimit[j.idx_v] = limit;
    }
  } else if (limits) {
    fail(path, "torque_limits must be a number or a map joint: limit");
  }
  for (const Joint& j : model.joints)
    if (actuated(j) && !std::isfinite(model.effortLimit[j.idx_v]))
      fail(path, "joint '" + j.name +
                     "' has no torque limit: torque_limits does not give one and the URDF gives "
                     "no effort");
}

// The default posture before its base height is corrected: the SRDF state (if any), then the
// YAML's joints and base over it. `base_source` says where the base height came from.
Eigen::VectorXd readPosture(const YAML::Node& root, const Robot& robot, const std::string& path,
                            std::string& base_source) {
  const Model& model = robot.model;
  const bool from_srdf = !robot.reference_posture.empty();
  const YAML::Node posture = root["default_posture"];
  if (!posture && !from_srdf)
    fail(path, "missing key 'default_posture' (or give 'srdf' and 'reference_posture')");
  if (posture) checkKeys(posture, {"base", "joints"}, path, "default_posture.");

  Eigen::VectorXd q = neutral(model);
  if (from_srdf) {
    q = model.referenceConfigurations.at(robot.reference_posture);
    base_source = "SRDF '" + robot.srdf_path + "' group_state '" + robot.reference_posture + "'";
  }
  const YAML::Node joints = posture ? posture["joints"] : YAML::Node(YAML::NodeType::Undefined);
  if (!joints && !from_srdf) fail(path, "missing key 'joints' in default_posture");
  if (joints) {
    if (!joints.IsMap()) fail(path, "default_posture.joints must be a map joint: angle");
    for (const auto& kv : joints) {
      const Joint& j =
          namedJoint(model, kv.first.as<std::string>(), path, "default_posture.joints");
      q[j.idx_q] = kv.second.as<double>();
    }
  }
  // Without an SRDF state, every joint must be named: a missing one is an error, not a silent 0.
  if (!from_srdf)
    for (const Joint& j : model.joints)
      if (actuated(j) && !joints[j.name])
        fail(path, "default_posture.joints has no entry for joint '" + j.name + "'");

  const YAML::Node base = posture ? posture["base"] : YAML::Node(YAML::NodeType::Undefined);
  if (base && !model.hasFreeFlyer())
    fail(path, "default_posture.base is only for a free-flyer root_joint");
  if (base) {
    const auto b = base.as<std::vector<double>>();
    if (b.size() != 7) fail(path, "default_posture.base needs 7 numbers [x y z qx qy qz qw]");
    for (int k = 0; k < 7; ++k) q[k] = b[k];
    if (std::abs(q.segment<4>(3).norm() - 1.0) > 1e-6)
      fail(path, "default_posture.base quaternion is not unit");
    base_source = "default_posture.base";
  } else if (model.hasFreeFlyer() && !from_srdf) {
    fail(path, "missing key 'base' in default_posture");
  }
  if (!q.allFinite()) fail(path, "default_posture has non-finite values");
  normalize(model, q);
  return q;
}

// Moves a free-flyer's base vertically so that the lowest contact frame is at z = 0: SRDF heights
// are rounded (or meant for another foot frame), and a robot that starts in the air or in the
// ground spoils the first solves. A given height that misses by more than 1 mm is worth telling the
// user.
void putOnTheGround(Robot& robot, const std::string& base_source) {
  const Model& model = robot.model;
  if (!model.hasFreeFlyer() || robot.contacts.empty()) return;
  Data data(model);
  framesForwardKinematics(model, data, robot.default_q);
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& c : robot.contacts)
    lowest = std::min(lowest, data.oMf[model.getFrameId(c.frame)].p.z());
  const double given = robot.default_q[2], computed = given - lowest;
  robot.default_q[2] = computed;
  if (std::abs(lowest) > 1e-3) {
    std::ostringstream w;
    w << std::fixed << std::setprecision(4) << "warning: robot config '" << robot.yaml_path
      << "': the base height " << given << " m of " << base_source << " leaves the lowest contact "
      << std::setprecision(1) << std::abs(lowest) * 100 << " cm "
      << (lowest > 0 ? "above" : "below") << " the ground; using the computed base height "
      << std::setprecision(4) << computed << " m\n";
    std::cerr << w.str();
  }
}
// The gaits pair feet by their index (locomotion/gait.cpp: trot lifts 0 and 3, then 1 and 2; pace 0
// and 2): four feet must be listed front-left, front-right, hind-left, hind-right and two left,
// right. A HyQ listed FL, HL, FR, HR trotted as a bound and was still "tracked" (issue 34). Judged
// by the feet's positions in the base frame at the default posture.
void checkFootOrder(const Robot& robot) {
  const Model& model = robot.model;
  const int n = static_cast<int>(robot.contacts.size());
  if (!model.hasFreeFlyer() || (n != 2 && n != 4)) return;
  Data data(model);
  framesForwardKinematics(model, data, robot.default_q);
  const SE3& base = data.oMi[1];
  std::vector<Eigen::Vector3d> p;
  for (const ContactSpec& c : robot.contacts)
    p.push_back(base.R.transpose() * (data.oMf[model.getFrameId(c.frame)].p - base.p));
  std::vector<int> order(n);  // the right order: by position
  for (int i = 0; i < n; ++i) order[i] = i;
  if (n == 2) {
    std::sort(order.begin(), order.end(), [&p](int a, int b) { return p[a].y() > p[b].y(); });
  } else {
    std::sort(order.begin(), order.end(), [&p](int a, int b) { return p[a].x() > p[b].x(); });
    for (int pair : {0, 2})
      if (p[order[pair]].y() < p[order[pair + 1]].y()) std::swap(order[pair], order[pair + 1]);
  }
  bool right = true;
  for (int i = 0; i < n; ++i) right = right && order[i] == i;
  if (right) return;
  static const char* kQuad[] = {"front-left", "front-right", "hind-left", "hind-right"};
  static const char* kBiped[] = {"left", "right"};
  const char* const* names = n == 4 ? kQuad : kBiped;
  std::ostringstream what;
  what << std::fixed << std::setprecision(3) << "contacts are not in the order the gaits assume ("
       << (n == 4 ? "front-left, front-right, hind-left, hind-right" : "left, right")
       << "): at the default posture, in the base frame [m],";
  for (int i = 0; i < n; ++i) {
    const int slot = static_cast<int>(std::find(order.begin(), order.end(), i) - order.begin());
    what << (i ? ";" : "") << " contacts[" << i << "] '" << robot.contacts[i].frame << "' at (x "
         << p[i].x() << ", y " << p[i].y() << ") is " << names[slot];
  }
  what << ". List them as:";
  for (int i = 0; i < n; ++i) what << (i ? "," : "") << " " << robot.contacts[order[i]].frame;
  fail(robot.yaml_path, what.str());
}

// The support polygon's signed distance to a point in the ground plane: negative inside, the
// distance to the polygon (a segment for two point feet, a point for one) outside.
double outsideSupport(std::vector<Eigen::Vector2d> pts, const Eigen::Vector2d& x) {
  // Convex hull (monotone chain), counter-clockwise.
  std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Eigen::Vector2d> hull;
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t start = hull.size();
    for (const Eigen::Vector2d& q : pts) {
      while (hull.size() >= start + 2 && cross(hull[hull.size() - 2], hull.back(), q) <= 1e-12)
        hull.pop_back();
      hull.push_back(q);
    }
    hull.pop_back();
    std::reverse(pts.begin(), pts.end());
  }
  if (hull.empty()) hull = pts;  // all points equal
  double nearest = std::numeric_limits<double>::infinity();
  bool inside = hull.size() >= 3;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
    const Eigen::Vector2d ab = b - a;
    const double t =
        ab.squaredNorm() > 0 ? std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    nearest = std::min(nearest, (a + t * ab - x).norm());
    if (hull.size() >= 3 && cross(a, b, x) < 0) inside = false;
  }
  return inside ? -nearest : nearest;
}

// The support polygon's corners in the ground plane: point feet, and the four corners of each
// sole (data: frame placements up to date).
std::vector<Eigen::Vector2d> supportPoints(const Robot& robot, const Data& data) {
  std::vector<Eigen::Vector2d> support;
  for (const ContactSpec& c : robot.contacts) {
    const SE3& f = data.oMf[robot.model.getFrameId(c.frame)];
    if (c.dim == 3) {
      support.push_back(f.p.head<2>());
      continue;
    }
    for (const double sx : {-1.0, 1.0})
      for (const double sy : {-1.0, 1.0})
        support.push_back((f.p + f.R * Eigen::Vector3d(sx * robot.sole_half_extents.x(),
                                                       sy * robot.sole_half_extents.y(), 0.0))
                              .head<2>());
  }
  return support;
}

// Standing still at the default posture needs the centre of mass over the support polygon (the
// feet, or the soles' corners). Bolt's posture put it 1.9 cm behind its feet and the robot pitched
// back 31 degrees at start-up (issue 34). Beyond kBalanceWarning outside: a warning with the
// distance; beyond kBalanceError: an error (no controller holds a robot started that way).
constexpr double kBalanceWarning = 0.005, kBalanceError = 0.05;

void checkBalance(const Robot& robot) {
  const double d = comOutsideSupport(robot, robot.default_q);
  if (d <= kBalanceWarning) return;
  const Model& model = robot.model;
  Data data(model);
  const Eigen::Vector3d com = centerOfMass(model, data, robot.default_q);
  updateFramePlacements(model, data);
  const std::vector<Eigen::Vector2d> support = supportPoints(robot, data);
  // Where it is, in the base's heading: behind or ahead, left or right of the feet's centre.
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& q : support) centre += q / static_cast<double>(support.size());
  const SE3& base = data.oMi[1];
  const Eigen::Vector2d heading = base.R.col(0).head<2>().normalized();
  const Eigen::Vector2d offset = com.head<2>() - centre;
  const double ahead = offset.dot(heading),
               left = offset.dot(Eigen::Vector2d(-heading.y(), heading.x()));
  std::ostringstream what;
  what << std::fixed << std::setprecision(1) << "the default posture's centre of mass is "
       << d * 100 << " cm outside the support polygon of its "
       << (robot.contacts.size() == 2 && robot.contacts[0].dim == 3 ? "two point feet (a line)"
                                                                    : "feet")
       << " (" << std::abs(ahead) * 100 << " cm " << (ahead < 0 ? "behind" : "ahead of") << ", "
       << std::abs(left) * 100 << " cm " << (left < 0 ? "right" : "left")
       << " of the feet's centre): the robot starts falling; move the feet under it (hip and knee "
          "angles, or the SRDF posture)";
  if (d > kBalanceError)
    fail(robot.yaml_path, what.str() + " (more than " +
                              std::to_string(static_cast<int>(kBalanceError * 100)) +
                              " cm: refused)");
  std::cerr << "warning: robot config '" << robot.yaml_path << "': " << what.str() << "\n";
}
}  // namespace

double comOutsideSupport(const Robot& robot, const Eigen::VectorXd& q) {
  const Model& model = robot.model;
  if (!model.hasFreeFlyer() || robot.contacts.empty())
    return -std::numeric_limits<double>::infinity();
  Data data(model);
  const Eigen::Vector3d com = centerOfMass(model, data, q);
  updateFramePlacements(model, data);
  return outsideSupport(supportPoints(robot, data), com.head<2>());
}

Robot loadRobot(const std::string& yaml_path, const std::vector<std::string>& robots_dirs) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::BadFile&) {
    fail(yaml_path, "file does not exist or cannot be read");
  } catch (const YAML::Exception& e) {
    fail(yaml_path, std::string("malformed YAML: ") + e.what());
  }
  Robot robot;
  robot.yaml_path = yaml_path;
  const std::string yaml_dir = std::filesystem::path(yaml_path).parent_path().string();
  // Files named by the YAML: the error says which key named the missing one.
  auto resolve = [&](const char* key) {
    const std::string uri = need(root, key, yaml_path).as<std::string>();
    try {
      return resolveRobotFile(uri, yaml_dir, robots_dirs);
    } catch (const RobotFileNotFound& e) {
      throw RobotFileNotFound("robot config '" + yaml_path + "': " + key + ": " + e.what(),
                              e.tried());
    } catch (const ConfigError& e) {
      fail(yaml_path, std::string(key) + ": " + e.what());
    }
  };
  try {
    checkKeys(root,
              {"name", "urdf", "srdf", "reference_posture", "root_joint", "locked_joints",
               "contacts", "sole_half_extents", "torque_limits", "default_posture", "joint_pd"},
              yaml_path, "");
    robot.name = need(root, "name", yaml_path).as<std::string>();
    robot.urdf_path = resolve("urdf");
    const std::string root_joint = need(root, "root_joint", yaml_path).as<std::string>();
    if (root_joint != "free-flyer" && root_joint != "fixed")
      fail(yaml_path, "root_joint must be 'free-flyer' or 'fixed', not '" + root_joint + "'");
    // Joints held at an angle (grippers, a head): fixed joints of the model, their bodies merged
    // into the parent; a URDF's <mimic> joints follow their locked leader, and an unlocked one is
    // refused by the URDF builder (issue 34: full TALOS's 12 gripper mimics became free motors).
    std::map<std::string, double> locked;
    if (const YAML::Node l = root["locked_joints"]) {
      if (!l.IsMap()) fail(yaml_path, "locked_joints must be a map joint: angle [rad or m]");
      for (const auto& kv : l) locked[kv.first.as<std::string>()] = kv.second.as<double>();
    }
    robot.model = buildModelFromUrdf(
        robot.urdf_path, root_joint == "fixed" ? RootJoint::Fixed : RootJoint::FreeFlyer, locked);
    Model& model = robot.model;

    if (root["srdf"]) {
      robot.srdf_path = resolve("srdf");
      const SrdfReport srdf = loadReferenceConfigurations(model, robot.srdf_path);
      if (root["reference_posture"]) {
        robot.reference_posture = root["reference_posture"].as<std::string>();
        if (std::find(srdf.states.begin(), srdf.states.end(), robot.reference_posture) ==
            srdf.states.end())
          fail(yaml_path, "reference_posture '" + robot.reference_posture +
                              "' is not a group_state of SRDF '" + robot.srdf_path + "' (it has: " +
                              (srdf.states.empty() ? "none" : joined(srdf.states)) + ")");
      }
    } else if (root["reference_posture"]) {
      fail(yaml_path, "reference_posture needs an 'srdf' key (the file of its group_state)");
    }

    robot.contacts = readContacts(need(root, "contacts", yaml_path), model, yaml_path);
    if (root["sole_half_extents"]) {
      const auto e = root["sole_half_extents"].as<std::vector<double>>();
      if (e.size() != 2 || !(e[0] > 0) || !(e[1] > 0))
        fail(yaml_path, "sole_half_extents must be two positive numbers");
      robot.sole_half_extents << e[0], e[1];
    }
    for (std::size_t i = 0; i < robot.contacts.size(); ++i)
      if (robot.contacts[i].dim == 6 && !root["sole_half_extents"])
        fail(yaml_path, "contacts[" + std::to_string(i) + "] '" + robot.contacts[i].frame +
                            "' has dim 6 (a flat sole) but 'sole_half_extents' is not given: the "
                            "sole's half length and half width [m] along the contact frame's x "
                            "and y (half the foot's collision box), e.g. sole_half_extents: [0.1, "
                            "0.05]; or dim 3 for a point foot");
    applyTorqueLimits(root["torque_limits"], model, yaml_path);
    if (const YAML::Node pd = root["joint_pd"]) {
      checkKeys(pd, {"kp", "kd"}, yaml_path, "joint_pd.");
      robot.joint_kp = need(pd, "kp", yaml_path).as<double>();
      robot.joint_kd = need(pd, "kd", yaml_path).as<double>();
      if (!(robot.joint_kp > 0.0) || !(robot.joint_kd >= 0.0) || !std::isfinite(robot.joint_kp) ||
          !std::isfinite(robot.joint_kd))
        fail(yaml_path, "joint_pd: kp must be positive and kd not negative, both finite");
    }

    std::string base_source;
    robot.default_q = readPosture(root, robot, yaml_path, base_source);
    putOnTheGround(robot, base_source);
    model.referenceConfigurations["default"] = robot.default_q;
    checkFootOrder(robot);
    checkBalance(robot);
  } catch (const YAML::Exception& e) {
    fail(yaml_path, std::string("bad value: ") + e.what());
  } catch (const UrdfError& e) {
    fail(yaml_path, e.what());
  }
  return robot;
}

}  // namespace stride
