#include "solver/multibody/urdf.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <vector>

namespace stride {

namespace {

// A joint the URDF gives no limit: unbounded.
constexpr double kUnlimited = std::numeric_limits<double>::infinity();

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw UrdfError("URDF '" + source + "': " + what);
}

std::string where(const TiXmlElement* e) {
  return " (line " + std::to_string(e->Row()) + ")";
}

// A number attribute that must be present and finite. urdfdom reads a non-number as 0 without a
// word, and a missing inertia term as 0: a robot would silently lose mass.
double numberAttribute(const TiXmlElement* e, const char* attr, const std::string& source,
                       const std::string& context) {
  const char* text = e->Attribute(attr);
  if (!text) fail(source, context + " has no '" + attr + "' attribute" + where(e));
  char* end = nullptr;
  const double x = std::strtod(text, &end);
  while (end && std::isspace(static_cast<unsigned char>(*end))) ++end;
  if (end == text || *end != '\0' || !std::isfinite(x))
    fail(source, context + " has " + attr + "='" + text + "', not a finite number" + where(e));
  return x;
}

void validateInertial(const TiXmlElement* link, const std::string& source) {
  const TiXmlElement* in = link->FirstChildElement("inertial");
  if (!in) return;  // a massless frame link
  const std::string ctx = "link '" + std::string(link->Attribute("name")) + "' <inertial>";
  const TiXmlElement* mass = in->FirstChildElement("mass");
  if (!mass) fail(source, ctx + " has no <mass>" + where(in));
  if (numberAttribute(mass, "value", source, ctx + " <mass>") < 0)
    fail(source, ctx + " has a negative mass" + where(mass));
  const TiXmlElement* inertia = in->FirstChildElement("inertia");
  if (!inertia) fail(source, ctx + " has no <inertia>" + where(in));
  double I[6];
  int k = 0;
  for (const char* a : {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"})
    I[k++] = numberAttribute(inertia, a, source, ctx + " <inertia>");
  Eigen::Matrix3d M;
  M << I[0], I[3], I[4], I[3], I[1], I[5], I[4], I[5], I[2];
  const double smallest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(M).eigenvalues().minCoeff();
  if (smallest < -1e-9 * std::max(1.0, M.norm()))
    fail(source,
         ctx + " has an inertia tensor that is not positive semi-definite" + where(inertia));
}

// What the structural checks learn on the way: each joint's type, the moving mimic joints.
struct UrdfInfo {
  std::map<std::string, std::string> joint_type;
  std::vector<MimicJoint> mimics;  // moving joints only, file order
};

// Structural checks on the raw XML before urdfdom sees it, so that every error names the element
// and its line: urdfdom itself only logs to the console and returns null.
UrdfInfo validateStructure(const std::string& xml, const std::string& source) {
  UrdfInfo info;
  std::vector<int> mimic_lines;
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error()) {
    fail(source, "malformed XML at line " + std::to_string(doc.ErrorRow()) + ", column " +
                     std::to_string(doc.ErrorCol()) + ": " + doc.ErrorDesc());
  }
  const TiXmlElement* robot = doc.RootElement();
  if (!robot || std::string(robot->Value()) != "robot")
    fail(source, "the root element must be <robot>");
  std::set<std::string> links;
  for (const TiXmlElement* l = robot->FirstChildElement("link"); l;
       l = l->NextSiblingElement("link")) {
    const char* name = l->Attribute("name");
    if (!name || !*name) fail(source, "<link> without a name" + where(l));
    if (!links.insert(name).second)
      fail(source, "link '" + std::string(name) + "' is defined twice" + where(l));
    validateInertial(l, source);
  }
  if (links.empty()) fail(source, "no <link> element");
  std::map<std::string, std::string> parent_joint_of;        // child link -> joint
  std::map<std::string, std::vector<std::string>> children;  // parent link -> child links
  std::set<std::string> joints;
  static const std::set<std::string> kSupported = {"revolute", "continuous", "prismatic", "fixed"};
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j;
       j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    if (!name || !*name) fail(source, "<joint> without a name" + where(j));
    const std::string jn = name;
    if (!joints.insert(jn).second) fail(source, "joint '" + jn + "' is defined twice" + where(j));
    const char* type = j->Attribute("type");
    if (!type) fail(source, "joint '" + jn + "' has no type" + where(j));
    if (!kSupported.count(type))
      fail(source, "joint '" + jn + "' has type '" + type + "'" + where(j) +
                       ", which Stride does not support (revolute, continuous, prismatic, fixed; a "
                       "floating base is the root joint chosen by the caller)");
    const TiXmlElement* p = j->FirstChildElement("parent");
    const TiXmlElement* c = j->FirstChildElement("child");
    const char* pl = p ? p->Attribute("link") : nullptr;
    const char* cl = c ? c->Attribute("link") : nullptr;
    if (!pl) fail(source, "joint '" + jn + "' has no <parent link=...>" + where(j));
    if (!cl) fail(source, "joint '" + jn + "' has no <child link=...>" + where(j));
    if (!links.count(pl))
      fail(source,
           "joint '" + jn + "' names a parent link '" + pl + "' that does not exist" + where(j));
    if (!links.count(cl))
      fail(source,
           "joint '" + jn + "' names a child link '" + cl + "' that does not exist" + where(j));
    if (parent_joint_of.count(cl))
      fail(source, "link '" + std::string(cl) + "' is the child of two joints, '" +
                       parent_joint_of[cl] + "' and '" + jn + "'" + where(j) +
                       ": kinematic loops are not supported");
    parent_joint_of[cl] = jn;
    children[pl].push_back(cl);
    info.joint_type[jn] = type;
    if (const TiXmlElement* m = j->FirstChildElement("mimic")) {
      const std::string ctx = "joint '" + jn + "' <mimic>";
      const char* leader = m->Attribute("joint");
      if (!leader || !*leader) fail(source, ctx + " has no 'joint' attribute" + where(m));
      MimicJoint mimic{jn, leader, 1.0, 0.0};
      if (m->Attribute("multiplier"))
        mimic.multiplier = numberAttribute(m, "multiplier", source, ctx);
      if (m->Attribute("offset")) mimic.offset = numberAttribute(m, "offset", source, ctx);
      // A fixed joint owns no coordinate: its tag couples nothing (talos_reduced's fingers).
      if (std::string(type) != "fixed") {
        info.mimics.push_back(mimic);
        mimic_lines.push_back(m->Row());
      }
    }
  }
  for (std::size_t k = 0; k < info.mimics.size(); ++k) {
    const MimicJoint& m = info.mimics[k];
    const std::string at = " (line " + std::to_string(mimic_lines[k]) + ")";
    if (!joints.count(m.leader))
      fail(source, "joint '" + m.name + "' mimics '" + m.leader + "', which is not a joint" + at);
    if (m.leader == m.name) fail(source, "joint '" + m.name + "' mimics itself" + at);
  }
  std::vector<std::string> roots;
  for (const auto& l : links)
    if (!parent_joint_of.count(l)) roots.push_back(l);
  if (roots.empty())
    fail(source, "no root link: every link is the child of a joint, so the joints form a loop");
  if (roots.size() > 1) {
    std::string names;
    for (const auto& r : roots) names += (names.empty() ? "'" : ", '") + r + "'";
    fail(source, "several root links (" + names + "): the links must form one tree");
  }
  // Every link must hang from the root; a link on a cycle cannot.
  std::set<std::string> reached;
  std::function<void(const std::string&)> visit = [&](const std::string& l) {
    if (!reached.insert(l).second) return;
    for (const auto& c : children[l]) visit(c);
  };
  visit(roots[0]);
  for (const auto& l : links)
    if (!reached.count(l))
      fail(source, "link '" + l + "' (child of joint '" + parent_joint_of[l] +
                       "') is not connected to the root link '" + roots[0] + "': kinematic loop");
  return info;
}

std::string num(double x) {
  std::ostringstream out;
  out << std::setprecision(12) << x;
  return out.str();
}

// The angle of every locked joint: the caller's, then the mimics of locked (or fixed) leaders,
// through chains. Refuses bad names and angles, and moving mimic joints left free.
std::map<std::string, double> lockedAngles(const urdf::ModelInterface& urdf_model,
                                           const UrdfInfo& info, RootJoint root,
                                           const std::map<std::string, double>& locked_joints,
                                           MimicJoints mimic_joints, const std::string& source) {
  // Within its limits (none for continuous joints); `slack` for angles computed from a leader's.
  const auto checkRange = [&](const std::string& name, double angle, double slack,
                              const std::string& why) {
    const urdf::Joint& j = *urdf_model.getJoint(name);
    const char* unit = j.type == urdf::Joint::PRISMATIC ? " m" : " rad";
    if (!std::isfinite(angle))
      fail(source, "joint '" + name + "' locked at " + num(angle) + why + ": not a finite number");
    if (!j.limits || j.type == urdf::Joint::CONTINUOUS) return;
    if (angle < j.limits->lower - slack || angle > j.limits->upper + slack)
      fail(source, "joint '" + name + "' locked at " + num(angle) + unit + why +
                       ", outside its limits [" + num(j.limits->lower) + ", " +
                       num(j.limits->upper) + "]" + unit);
  };
  std::map<std::string, double> angles;
  for (const auto& [name, angle] : locked_joints) {
    const auto type = info.joint_type.find(name);
    if (type == info.joint_type.end()) {
      if (root == RootJoint::FreeFlyer && name == "root_joint")
        fail(source,
             "locked joint 'root_joint' is the free-flyer root, which cannot be locked "
             "(build with a fixed root instead)");
      fail(source, "locked joint '" + name + "' is not a joint of this URDF");
    }
    if (type->second == "fixed")
      fail(source, "locked joint '" + name + "' is a fixed joint: there is nothing to lock");
    checkRange(name, angle, 0.0, "");
    angles[name] = angle;
  }
  // Mimics follow their leaders; an explicitly locked mimic must agree with a locked leader.
  for (bool changed = true; changed;) {
    changed = false;
    for (const MimicJoint& m : info.mimics) {
      double leader_angle = 0.0;  // a fixed leader stays at 0
      if (info.joint_type.at(m.leader) != "fixed") {
        const auto it = angles.find(m.leader);
        if (it == angles.end()) continue;
        leader_angle = it->second;
      }
      const double angle = m.multiplier * leader_angle + m.offset;
      const std::string why = " (it mimics '" + m.leader + "' locked at " + num(leader_angle) +
                              ": multiplier " + num(m.multiplier) + ", offset " + num(m.offset) +
                              ")";
      const auto own = angles.find(m.name);
      if (own != angles.end()) {
        if (std::abs(own->second - angle) > 1e-9 * std::max(1.0, std::abs(angle)))
          fail(source, "joint '" + m.name + "' is locked at " + num(own->second) +
                           " but must be at " + num(angle) + why);
        continue;
      }
      checkRange(m.name, angle, 1e-9, why);
      angles[m.name] = angle;
      changed = true;
    }
  }
  std::string free_mimics, leaders;
  std::set<std::string> listed;
  for (const MimicJoint& m : info.mimics) {
    if (angles.count(m.name)) continue;
    free_mimics += std::string(free_mimics.empty() ? "" : "; ") + "joint '" + m.name +
                   "' mimics '" + m.leader + "' (multiplier " + num(m.multiplier) + ", offset " +
                   num(m.offset) + ")";
    if (listed.insert(m.leader).second) leaders += (leaders.empty() ? "'" : ", '") + m.leader + "'";
  }
  if (!free_mimics.empty() && mimic_joints == MimicJoints::FollowLockedLeader)
    fail(source, free_mimics + ": Stride has no coupled joints; lock " + leaders +
                     " (locked_joints) and " + (listed.size() > 1 ? "their" : "its") +
                     " mimics follow, or lock the mimic joints themselves");
  return angles;
}

// Collects urdfdom's console messages while it parses, to put them in our error.
class CaptureLog : public console_bridge::OutputHandler {
 public:
  CaptureLog() { console_bridge::useOutputHandler(this); }
  ~CaptureLog() override { console_bridge::restorePreviousOutputHandler(); }
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN)
      messages += (messages.empty() ? "" : "; ") + text;
  }
  std::string messages;
};

SE3 toSE3(const urdf::Pose& pose) {
  const Eigen::Quaterniond quat(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  return SE3(quat.normalized().toRotationMatrix(),
             Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z));
}

Inertia linkInertia(const urdf::Link& link) {
  if (!link.inertial) return Inertia::Zero();
  const urdf::Inertial& in = *link.inertial;
  Eigen::Matrix3d I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  // The URDF tensor is about the centre of mass, in the <inertial><origin> frame.
  return Inertia::FromMassComInertia(in.mass, Eigen::Vector3d::Zero(), I)
      .transformedBy(toSE3(in.origin));
}

struct Builder {
  Model& model;
  const std::string& source;
  const std::map<std::string, double>& locked;  // joint -> angle, mimics included

  // Adds `link` carried by joint `joint`, whose frame is at `placement` in that joint's frame.
  void addLink(const urdf::Link& link, int joint, int parent_frame, const SE3& placement) {
    model.appendBodyToJoint(joint, linkInertia(link), placement);
    Frame body;
    body.name = link.name;
    body.type = FrameType::Body;
    body.parentJoint = joint;
    body.parentFrame = parent_frame;
    body.placement = placement;
    const int body_frame = model.addFrame(body);
    for (const auto& uj : link.child_joints) {  // urdfdom lists them sorted by name
      const urdf::Link& child = *urdf_model->getLink(uj->child_link_name);
      SE3 at = placement * toSE3(uj->parent_to_joint_origin_transform);
      const Eigen::Vector3d axis(uj->axis.x, uj->axis.y, uj->axis.z);
      const bool fixed = uj->type == urdf::Joint::FIXED;
      if (!fixed && axis.norm() < 1e-9) fail(source, "joint '" + uj->name + "' has a zero <axis>");
      const auto lock = locked.find(uj->name);
      if (!fixed && lock != locked.end()) {  // a fixed joint at the joint's motion for that angle
        const Eigen::Vector3d u = axis.normalized();
        at = at * (uj->type == urdf::Joint::PRISMATIC
                       ? SE3(Eigen::Matrix3d::Identity(), lock->second * u)
                       : SE3(Eigen::AngleAxisd(lock->second, u).toRotationMatrix(),
                             Eigen::Vector3d::Zero()));
      }
      if (fixed || lock != locked.end()) {
        Frame fj;
        fj.name = uj->name;
        fj.type = FrameType::FixedJoint;
        fj.parentJoint = joint;
        fj.parentFrame = body_frame;
        fj.placement = at;
        addLink(child, joint, model.addFrame(fj), at);
        continue;
      }
      const JointType type =
          uj->type == urdf::Joint::PRISMATIC ? JointType::Prismatic : JointType::Revolute;
      const int id = model.addJoint(joint, type, at, uj->name, axis);
      const int jf = model.getFrameId(uj->name, FrameType::Joint);
      model.frames[jf].parentFrame = body_frame;
      double lo = -kUnlimited, hi = kUnlimited, vel = kUnlimited, eff = kUnlimited;
      if (uj->limits) {
        if (uj->type != urdf::Joint::CONTINUOUS) lo = uj->limits->lower, hi = uj->limits->upper;
        if (uj->limits->velocity > 0) vel = uj->limits->velocity;
        if (uj->limits->effort > 0) eff = uj->limits->effort;
      }
      if (lo > hi) fail(source, "joint '" + uj->name + "' has lower limit above its upper limit");
      model.setJointLimits(id, lo, hi, vel, eff);
      addLink(child, id, jf, SE3::Identity());
    }
  }
  const urdf::ModelInterface* urdf_model = nullptr;
};

}  // namespace

namespace {
Model buildModel(const std::string& xml, RootJoint root,
                 const std::map<std::string, double>& locked_joints, MimicJoints mimic_joints,
                 const std::string& source) {
  const UrdfInfo info = validateStructure(xml, source);
  urdf::ModelInterfaceSharedPtr urdf_model;
  {
    CaptureLog capture;
    urdf_model = urdf::parseURDF(xml);
    if (!urdf_model) fail(source, "urdfdom could not parse it: " + capture.messages);
  }
  const std::map<std::string, double> locked =
      lockedAngles(*urdf_model, info, root, locked_joints, mimic_joints, source);
  Model model;
  model.name = urdf_model->getName();
  Builder builder{model, source, locked};
  builder.urdf_model = urdf_model.get();
  const urdf::Link& root_link = *urdf_model->getRoot();
  try {
    if (root == RootJoint::FreeFlyer) {
      const int ff = model.addJoint(0, JointType::FreeFlyer, SE3::Identity(), "root_joint");
      builder.addLink(root_link, ff, model.getFrameId("root_joint"), SE3::Identity());
    } else {
      builder.addLink(root_link, 0, 0, SE3::Identity());
    }
  } catch (const std::invalid_argument& e) {
    fail(source, e.what());
  }
  return model;
}
}  // namespace

Model buildModelFromUrdfString(const std::string& xml, RootJoint root,
                               const std::map<std::string, double>& locked_joints,
                               const std::string& source) {
  return buildModel(xml, root, locked_joints, MimicJoints::FollowLockedLeader, source);
}

Model buildModelFromUrdfString(const std::string& xml, RootJoint root, const std::string& source) {
  return buildModel(xml, root, {}, MimicJoints::Independent, source);
}

namespace {
std::string readUrdf(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UrdfError("URDF '" + path + "': file does not exist or cannot be read");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}
}  // namespace

Model buildModelFromUrdf(const std::string& path, RootJoint root,
                         const std::map<std::string, double>& locked_joints) {
  return buildModelFromUrdfString(readUrdf(path), root, locked_joints, path);
}

Model buildModelFromUrdf(const std::string& path, RootJoint root) {
  return buildModelFromUrdfString(readUrdf(path), root, path);
}

std::vector<MimicJoint> urdfMimicJointsFromString(const std::string& xml,
                                                  const std::string& source) {
  return validateStructure(xml, source).mimics;
}

std::vector<MimicJoint> urdfMimicJoints(const std::string& path) {
  return urdfMimicJointsFromString(readUrdf(path), path);
}

}  // namespace stride
