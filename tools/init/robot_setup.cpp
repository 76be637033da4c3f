#include "tools/init/robot_setup.hpp"

#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include "config/package_path.hpp"
#include "config/robot_config.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/srdf.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride::init {

namespace fs = std::filesystem;

namespace {

std::string fmt(double x, int precision = 3) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << x;
  return s.str();
}

std::string joined(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

bool actuated(const Joint& j) {
  return j.type == JointType::Revolute || j.type == JointType::Prismatic;
}

// The file a URI names, and what the robot YAML should say: a package:// URI as given (found again
// through --robots-dir), a path made absolute (the YAML may live anywhere).
std::string resolve(const std::string& uri, const std::vector<std::string>& dirs,
                    std::string& entry, const char* what) {
  try {
    const std::string path = resolveRobotFile(uri, fs::current_path().string(), dirs);
    entry = uri.rfind("package://", 0) == 0 ? uri : fs::absolute(path).lexically_normal().string();
    return path;
  } catch (const ConfigError& e) {
    throw InitError(std::string("--") + what + " '" + uri + "': " + e.what());
  }
}

// <end_effector parent_link="..."/> of the SRDF, in file order.
std::vector<std::string> srdfEndEffectors(const std::string& path) {
  TiXmlDocument doc(path);
  if (!doc.LoadFile()) throw InitError("SRDF '" + path + "': cannot parse it as XML");
  std::vector<std::string> links;
  const TiXmlElement* robot = doc.RootElement();
  for (const TiXmlElement* e = robot ? robot->FirstChildElement("end_effector") : nullptr; e;
       e = e->NextSiblingElement("end_effector"))
    if (const char* link = e->Attribute("parent_link")) links.push_back(link);
  return links;
}

struct Template {
  std::string name;    // config/controller/<name>.yaml, config/robots/<name>/<name>.yaml
  double leg = 0.0;    // base height at its default posture [m]
  double mass = 0.0;   // [kg]
  double forward = 0;  // its command script's forward speed [m/s] and turn rate [rad/s]
  double turn = 0;
  double speed_leg = 0.0;  // the leg length the speeds go with (0: this template's)
};

// The template's leg length and mass from its robot (the values below when it cannot be loaded,
// e.g. without --robots-dir for the package:// robots).
Template templateFor(int feet, double mass, const InitInput& in, Setup& setup) {
  Template t;
  if (feet == 4 && mass > 20.0)
    t = {"anymal_c", 0.575, 52.1, 0.8, 0.8};
  else if (feet == 4)
    t = {"solo12", 0.216, 2.5, 0.5, 1.0};
  else if (mass > 40.0)
    t = {"talos_reduced", 1.04, 90.3, 0.3, 0.3};
  else if (mass >= 10.0)
    t = {"stride_humanoid", 0.96, 40.0, 0.3, 0.3};
  else  // a small biped (Bolt): a small robot's rate and horizon, a biped's speeds
    t = {"solo12", 0.216, 2.5, 0.3, 0.3, 0.96};
  const std::string yaml = in.config_dir + "/robots/" + t.name + "/" + t.name + ".yaml";
  try {
    const Robot robot = loadRobot(yaml, in.robots_dirs);
    t.leg = robot.default_q[2];
    t.mass = robot.model.totalMass();
    setup.joint_kp = robot.joint_kp;
    setup.joint_kd = robot.joint_kd;
  } catch (const std::exception& e) {
    setup.notes.push_back("template robot '" + yaml + "' not loaded (" + e.what() +
                          "); using its recorded leg length " + fmt(t.leg) + " m and mass " +
                          fmt(t.mass, 1) + " kg");
  }
  return t;
}

// Feet in the gaits' order (checkFootOrder in config/robot_config.cpp): four feet front-left,
// front-right, hind-left, hind-right; two left, right.
void orderFeet(std::vector<Foot>& feet) {
  if (feet.size() == 2) {
    std::sort(feet.begin(), feet.end(),
              [](const Foot& a, const Foot& b) { return a.in_base.y() > b.in_base.y(); });
  } else if (feet.size() == 4) {
    std::sort(feet.begin(), feet.end(),
              [](const Foot& a, const Foot& b) { return a.in_base.x() > b.in_base.x(); });
    for (int pair : {0, 2})
      if (feet[pair].in_base.y() < feet[pair + 1].in_base.y())
        std::swap(feet[pair], feet[pair + 1]);
  }
}

// The first revolute joint from the base down to `frame` whose axis is the base's y at q, and the
// sign of that axis along y; -1 when there is none.
int hipPitch(const Model& model, const Data& data, int frame, double& sign) {
  std::vector<int> chain;
  for (int j = model.frames[frame].parentJoint; j > 1; j = model.joints[j].parent)
    chain.push_back(j);
  std::reverse(chain.begin(), chain.end());
  const Eigen::Matrix3d base_R = data.oMi[1].R;
  for (int j : chain) {
    if (model.joints[j].type != JointType::Revolute) continue;
    const Eigen::Vector3d axis = base_R.transpose() * data.oMi[j].R * model.joints[j].axis;
    if (std::abs(axis.y()) > 0.95) {
      sign = axis.y() > 0 ? 1.0 : -1.0;
      return j;
    }
  }
  return -1;
}

std::string pyFloat(double x) {  // a YAML number that reads back exactly enough
  std::ostringstream s;
  s << std::setprecision(9) << x;
  std::string r = s.str();
  if (r.find_first_of(".e") == std::string::npos) r += ".0";
  return r;
}

double roundTo(double x, double step) {
  return std::max(step, std::round(x / step) * step);
}

}  // namespace

std::vector<std::string> outputFiles(const InitInput& in, const std::string& name) {
  return {in.out_dir + "/" + name + ".yaml", in.out_dir + "/" + name + "_controller.yaml",
          in.out_dir + "/" + name + "_commands.yaml"};
}

Setup analyse(const InitInput& in) {
  Setup s;
  s.urdf_path = resolve(in.urdf_uri, in.robots_dirs, s.urdf_entry, "urdf");
  s.srdf_path = resolve(in.srdf_uri, in.robots_dirs, s.srdf_entry, "srdf");

  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDFFile(s.urdf_path);
  if (!urdf) throw InitError("URDF '" + s.urdf_path + "': urdfdom cannot parse it");
  s.name = in.name.empty() ? urdf->getName() : in.name;
  if (s.name.empty() || s.name.find_first_of("/ \t") != std::string::npos)
    throw InitError("robot name '" + s.name + "' is not a file name: pass --name");

  Model model;
  try {
    // A <mimic> joint follows its leader: lock the first leader of each chain not locked already
    // (full TALOS: the two gripper joints, and their 12 mimics follow).
    s.locked = in.locked;
    const std::vector<MimicJoint> mimics = urdfMimicJoints(s.urdf_path);
    for (const MimicJoint& m : mimics) {
      if (s.locked.count(m.name)) continue;
      std::string leader = m.leader;
      for (bool more = true; more;) {
        more = false;
        for (const MimicJoint& n : mimics)
          if (n.name == leader && !s.locked.count(leader)) {
            leader = n.leader;
            more = true;
            break;
          }
      }
      if (s.locked.emplace(leader, 0.0).second)
        s.notes.push_back("joint '" + leader + "' locked at 0 (its <mimic> joints follow it; " +
                          "--lock " + leader + "=VALUE for another angle)");
    }
    model = buildModelFromUrdf(s.urdf_path, RootJoint::FreeFlyer, s.locked);
    const SrdfReport report = loadReferenceConfigurations(model, s.srdf_path);
    if (in.posture.empty()) {
      for (const char* p : {"standing", "half_sitting", "straight_standing"})
        if (model.referenceConfigurations.count(p)) {
          s.posture = p;
          break;
        }
      if (s.posture.empty())
        throw InitError("SRDF '" + s.srdf_path +
                        "' has no group_state standing, half_sitting or straight_standing (it "
                        "has: " +
                        (report.states.empty() ? "none" : joined(report.states)) +
                        "): pass --posture NAME");
    } else {
      s.posture = in.posture;
      if (!model.referenceConfigurations.count(s.posture))
        throw InitError(
            "--posture '" + s.posture + "' is not a group_state of SRDF '" + s.srdf_path +
            "' (it has: " + (report.states.empty() ? "none" : joined(report.states)) + ")");
    }
  } catch (const UrdfError& e) {
    throw InitError(e.what());
  }
  s.mass = model.totalMass();
  s.nq = model.nq;
  s.nv = model.nv;
  s.nu = model.nv - 6;

  // Torque limits: the URDF's efforts, unless they are placeholders.
  if (in.torque_limit <= 0.0) {
    std::vector<std::string> bad;
    double shown = 0.0;
    for (const Joint& j : model.joints) {
      if (!actuated(j)) continue;
      const double e = model.effortLimit[j.idx_v];
      if (!std::isfinite(e) || e <= 0.0 || (e >= 500.0 && s.mass < 100.0)) {
        bad.push_back(j.name);
        shown = e;
      }
    }
    if (!bad.empty())
      throw InitError("URDF '" + s.urdf_path + "': the effort of " + std::to_string(bad.size()) +
                      " joint(s) (" + joined(bad) + ") is a placeholder (" +
                      (std::isfinite(shown) && shown > 0.0 ? fmt(shown, 0) + " N m" : "missing") +
                      " on a " + fmt(s.mass, 2) +
                      " kg robot): pass --torque-limit NM, the actuators' real limit [N m]");
  }

  // Feet: --feet or the SRDF's end effectors.
  std::vector<std::string> foot_links = in.feet;
  if (foot_links.empty()) {
    foot_links = srdfEndEffectors(s.srdf_path);
    if (foot_links.empty())
      throw InitError("SRDF '" + s.srdf_path +
                      "' has no <end_effector parent_link=...>: pass --feet");
  }
  if (foot_links.size() != 2 && foot_links.size() != 4)
    throw InitError("stride-init sets up bipeds (2 feet) and quadrupeds (4 feet), not " +
                    std::to_string(foot_links.size()) + " (" + joined(foot_links) + ")");
  for (const std::string& f : foot_links) {
    if (!model.existFrame(f))
      throw InitError("foot '" + f + "' is not a link or frame of URDF '" + s.urdf_path + "'");
    Foot foot;
    foot.frame = f;
    if (in.sole_given) {
      foot.dim = 6;
    } else {
      const urdf::LinkConstSharedPtr link = urdf->getLink(f);
      const urdf::GeometrySharedPtr geometry =
          link && link->collision ? link->collision->geometry : nullptr;
      if (geometry && geometry->type == urdf::Geometry::BOX) {
        const auto* box = static_cast<const urdf::Box*>(geometry.get());
        const Eigen::Vector2d half(box->dim.x / 2, box->dim.y / 2);
        if (s.sole_half_extents.isZero()) s.sole_half_extents = half;
        s.sole_half_extents = s.sole_half_extents.cwiseMax(half);
        foot.dim = 6;
        s.notes.push_back("foot '" + f + "': a collision box, a flat sole of " + fmt(box->dim.x) +
                          " x " + fmt(box->dim.y) + " m (dim 6)");
      } else {
        const char* kind = !geometry                                  ? "no collision geometry"
                           : geometry->type == urdf::Geometry::SPHERE ? "a collision sphere"
                           : geometry->type == urdf::Geometry::MESH   ? "a collision mesh"
                                                                      : "a collision cylinder";
        s.notes.push_back("foot '" + f + "': " + kind + ", a point foot (dim 3)" +
                          (geometry && geometry->type != urdf::Geometry::SPHERE
                               ? "; pass --sole-half-extents X,Y for a flat sole"
                               : ""));
      }
    }
    s.feet.push_back(foot);
  }
  if (in.sole_given) s.sole_half_extents = in.sole_half_extents;
  // One kind of foot: a mix would need per-foot extents the YAML cannot give.
  const int dim = s.feet.front().dim;
  for (const Foot& f : s.feet)
    if (f.dim != dim)
      throw InitError("the feet mix point and flat feet: pass --sole-half-extents X,Y for all");

  // The posture, on the ground, the feet ordered.
  Eigen::VectorXd q = model.referenceConfigurations.at(s.posture);
  for (const Joint& j : model.joints) {
    if (!actuated(j)) continue;
    const double x = q[j.idx_q];
    if (x < model.lowerPositionLimit[j.idx_q] - 1e-6 ||
        x > model.upperPositionLimit[j.idx_q] + 1e-6)
      throw InitError("posture '" + s.posture + "': joint '" + j.name + "' at " + fmt(x) +
                      " is outside its limits [" + fmt(model.lowerPositionLimit[j.idx_q]) + ", " +
                      fmt(model.upperPositionLimit[j.idx_q]) + "]");
  }
  Data data(model);
  const auto ground = [&](Eigen::VectorXd& x) {
    framesForwardKinematics(model, data, x);
    double lowest = std::numeric_limits<double>::infinity();
    for (const Foot& f : s.feet)
      lowest = std::min(lowest, data.oMf[model.getFrameId(f.frame)].p.z());
    x[2] -= lowest;
    framesForwardKinematics(model, data, x);
  };
  ground(q);
  for (Foot& f : s.feet)
    f.in_base = data.oMi[1].R.transpose() * (data.oMf[model.getFrameId(f.frame)].p - data.oMi[1].p);
  orderFeet(s.feet);
  s.leg_length = q[2];
  s.base = q.head<7>();

  Robot robot;
  robot.model = model;
  robot.sole_half_extents = s.sole_half_extents;
  for (const Foot& f : s.feet) robot.contacts.push_back({f.frame, f.dim});
  s.com_outside = comOutsideSupport(robot, q);

  // A biped whose centre of mass is off its feet: both hip pitches turned by the same angle.
  if (s.com_outside > 0.005 && s.feet.size() == 2) {
    double signs[2];
    int hips[2];
    for (int i = 0; i < 2; ++i) {
      hips[i] = hipPitch(model, data, model.getFrameId(s.feet[i].frame), signs[i]);
      if (hips[i] < 0)
        throw InitError("posture '" + s.posture + "': the centre of mass is " +
                        fmt(s.com_outside * 100, 1) + " cm outside the support polygon, and leg '" +
                        s.feet[i].frame +
                        "' has no hip pitch joint (axis along the base's y) to "
                        "correct it with");
    }
    const Eigen::VectorXd q0 = q;
    const auto at = [&](double delta) {
      Eigen::VectorXd x = q0;
      for (int i = 0; i < 2; ++i) x[model.joints[hips[i]].idx_q] += signs[i] * delta;
      ground(x);
      return x;
    };
    // Signed offset of the CoM ahead of the feet's midpoint, along the base's heading.
    const auto offset = [&](double delta) {
      const Eigen::VectorXd x = at(delta);
      const Eigen::Vector3d com = centerOfMass(model, data, x);
      framesForwardKinematics(model, data, x);
      const Eigen::Vector3d mid = 0.5 * (data.oMf[model.getFrameId(s.feet[0].frame)].p +
                                         data.oMf[model.getFrameId(s.feet[1].frame)].p);
      Eigen::Vector3d fwd = data.oMi[1].R.col(0);
      fwd.z() = 0;
      return (com - mid).head<2>().dot(fwd.head<2>().normalized());
    };
    const double d0 = offset(0.0);
    double lo = 0.0, hi = std::numeric_limits<double>::quiet_NaN();
    for (double step = 0.01; step <= 0.5 + 1e-9 && std::isnan(hi); step += 0.01)
      for (double sgn : {1.0, -1.0})
        if (std::isnan(hi) && offset(sgn * step) * d0 <= 0.0) hi = sgn * step;
    if (std::isnan(hi))
      throw InitError("posture '" + s.posture + "': the centre of mass is " +
                      fmt(s.com_outside * 100, 1) + " cm " + (d0 < 0 ? "behind" : "ahead of") +
                      " the feet, and turning the hip pitches (" + model.joints[hips[0]].name +
                      ", " + model.joints[hips[1]].name +
                      ") by up to 0.5 rad does not bring it over them");
    for (int it = 0; it < 60 && std::abs(offset(hi)) > 2e-4; ++it) {
      const double mid = 0.5 * (lo + hi);
      (offset(mid) * d0 > 0.0 ? lo : hi) = mid;
    }
    const Eigen::VectorXd x = at(hi);
    for (int i = 0; i < 2; ++i) {
      const Joint& j = model.joints[hips[i]];
      if (x[j.idx_q] < model.lowerPositionLimit[j.idx_q] ||
          x[j.idx_q] > model.upperPositionLimit[j.idx_q])
        throw InitError("posture '" + s.posture + "': correcting the centre of mass (" +
                        fmt(s.com_outside * 100, 1) + " cm outside) needs " + j.name + " at " +
                        fmt(x[j.idx_q]) + ", outside its limits");
      s.corrected_joints[j.name] = x[j.idx_q];
    }
    const double before = s.com_outside;
    s.com_outside = comOutsideSupport(robot, x);
    if (s.com_outside > 0.002)
      throw InitError("posture '" + s.posture + "': the centre of mass is " + fmt(before * 100, 1) +
                      " cm outside the feet; the best hip pitch correction leaves it " +
                      fmt(s.com_outside * 100, 1) + " cm outside");
    std::ostringstream note;
    note << "posture '" << s.posture << "': the centre of mass was " << fmt(before * 100, 1)
         << " cm " << (d0 < 0 ? "behind" : "ahead of") << " the feet's line; turned "
         << model.joints[hips[0]].name << " and " << model.joints[hips[1]].name << " by "
         << fmt(hi, 4) << " rad (" << fmt(hi * 180 / M_PI, 2)
         << " deg about the base's y): " << model.joints[hips[0]].name << " "
         << fmt(q0[model.joints[hips[0]].idx_q], 4) << " -> "
         << fmt(x[model.joints[hips[0]].idx_q], 4) << ", " << model.joints[hips[1]].name << " "
         << fmt(q0[model.joints[hips[1]].idx_q], 4) << " -> "
         << fmt(x[model.joints[hips[1]].idx_q], 4) << "; now "
         << fmt(std::abs(offset(hi)) * 1000, 2) << " mm from the line";
    s.notes.push_back(note.str());
    q = x;
    s.leg_length = q[2];
    s.base = q.head<7>();
  } else if (s.com_outside > 0.05) {
    throw InitError("posture '" + s.posture + "': the centre of mass is " +
                    fmt(s.com_outside * 100, 1) +
                    " cm outside the support polygon (more than 5 cm): pick another --posture");
  } else if (s.com_outside > 0.005) {
    s.notes.push_back("posture '" + s.posture + "': the centre of mass is " +
                      fmt(s.com_outside * 100, 1) +
                      " cm outside the support polygon (not corrected)");
  }

  // The template.
  const Template t = templateFor(static_cast<int>(s.feet.size()), s.mass, in, s);
  s.template_name = t.name;
  s.ratio = std::sqrt(s.leg_length / t.leg);
  s.mass_ratio = s.mass / t.mass;
  s.joint_kp = std::round(s.joint_kp * s.mass_ratio * 1000.0) / 1000.0;
  s.joint_kd = std::round(s.joint_kd * s.mass_ratio * 1000.0) / 1000.0;
  const double speed_ratio = t.speed_leg > 0.0 ? std::sqrt(s.leg_length / t.speed_leg) : s.ratio;
  s.forward_speed = t.forward * speed_ratio;
  s.turn_rate = t.turn * speed_ratio;
  if (t.speed_leg > 0.0)
    s.notes.push_back(
        "a biped under 10 kg: the controller from solo12.yaml (200 Hz, 10 ms knots; "
        "stride_humanoid.yaml's 50 Hz let Bolt fall), the speeds a biped's (0.3 m/s "
        "and 0.3 rad/s at a 0.96 m leg) scaled by sqrt(leg / 0.96 m)");
  s.gait = s.feet.size() == 4 ? "trot" : "walk";
  return s;
}

void writeFiles(const InitInput& in, Setup& s) {
  fs::create_directories(in.out_dir);
  const std::vector<std::string> files = outputFiles(in, s.name);
  const std::string header = "# Written by stride-init (tools/init/README.md) from " +
                             s.urdf_entry + " and " + s.srdf_entry + ".\n";

  {  // the robot YAML
    std::ofstream f(files[0]);
    f << header << "name: " << s.name << "\nurdf: " << s.urdf_entry << "\nsrdf: " << s.srdf_entry
      << "\nroot_joint: free-flyer\n";
    if (!s.locked.empty()) {
      f << "# Held joints (--lock, and the leaders of the URDF's <mimic> joints): fixed in the "
           "model.\nlocked_joints:\n";
      for (const auto& [joint, value] : s.locked)
        f << "  " << joint << ": " << pyFloat(value) << "\n";
    }
    f << "# " << (s.feet.size() == 4 ? "FL, FR, HL, HR" : "left, right")
      << ": the order the gaits expect, from the feet's positions at the posture.\ncontacts:\n";
    for (const Foot& foot : s.feet)
      f << "  - {frame: " << foot.frame << ", dim: " << foot.dim << "}   # at (x "
        << fmt(foot.in_base.x()) << ", y " << fmt(foot.in_base.y()) << ") m in the base frame\n";
    if (s.feet.front().dim == 6)
      f << "sole_half_extents: [" << pyFloat(s.sole_half_extents.x()) << ", "
        << pyFloat(s.sole_half_extents.y()) << "]\n";
    if (in.torque_limit > 0.0)
      f << "torque_limits: " << pyFloat(in.torque_limit) << "   # --torque-limit\n";
    f << "reference_posture: " << s.posture << "\n";
    f << "# The base on the ground: the lowest foot at z = 0 (forward kinematics).\n"
      << "default_posture:\n  base: [0.0, 0.0, " << pyFloat(s.base[2]) << ", " << pyFloat(s.base[3])
      << ", " << pyFloat(s.base[4]) << ", " << pyFloat(s.base[5]) << ", " << pyFloat(s.base[6])
      << "]\n";
    if (!s.corrected_joints.empty()) {
      f << "  # The centre of mass over the feet: the hip pitches turned (stride-init's "
           "correction).\n"
        << "  joints:\n";
      for (const auto& [joint, value] : s.corrected_joints)
        f << "    " << joint << ": " << pyFloat(value) << "\n";
    }
    if (s.joint_kp > 0.0)
      f << "joint_pd: {kp: " << pyFloat(s.joint_kp) << ", kd: " << pyFloat(s.joint_kd)
        << "}   # the template's (" << s.template_name << ") scaled by the mass ratio\n";
    if (!f) throw InitError("cannot write '" + files[0] + "'");
  }

  {  // the controller YAML, from the template
    const std::string template_path = in.config_dir + "/controller/" + s.template_name + ".yaml";
    YAML::Node c;
    try {
      c = YAML::LoadFile(template_path);
    } catch (const YAML::Exception& e) {
      throw InitError("controller template '" + template_path + "': " + e.what());
    }
    c["robot"] = s.name + ".yaml";
    const double rate = c["rate_hz"].as<double>();
    const YAML::Node horizon = c["horizon"];
    const double dt0 =
        horizon["grid"] ? horizon["grid"][0]["dt"].as<double>() : horizon["dt"].as<double>();
    const int first_knots =
        horizon["grid"] ? horizon["grid"][0]["knots"].as<int>() : horizon["knots"].as<int>();
    if (c["gait"]) {
      for (auto g : c["gait"]) {
        YAML::Node timing = g.second;
        for (const char* key : {"support", "swing"})
          if (timing[key]) timing[key] = pyFloat(roundTo(timing[key].as<double>() * s.ratio, dt0));
      }
    }
    if (YAML::Node cmd = c["command"]) {
      if (cmd["max_velocity"]) {
        YAML::Node mv = cmd["max_velocity"];
        for (std::size_t i = 0; i < mv.size(); ++i)
          mv[i] = pyFloat(std::round(mv[i].as<double>() * s.ratio * 100.0) / 100.0);
      }
      if (cmd["max_body_height"])
        cmd["max_body_height"] = pyFloat(
            std::round(cmd["max_body_height"].as<double>() * s.ratio * s.ratio * 1000.0) / 1000.0);
    }
    if (YAML::Node contacts = c["contacts"]) {
      if (contacts["min_normal_force"])
        contacts["min_normal_force"] = pyFloat(
            std::round(contacts["min_normal_force"].as<double>() * s.mass_ratio * 100.0) / 100.0);
      if (contacts["swing_height"])
        contacts["swing_height"] =
            pyFloat(std::round(contacts["swing_height"].as<double>() * s.ratio * s.ratio * 1000.0) /
                    1000.0);
    }
    // Weights by mass: the control and friction-cone terms are squares of torques and forces,
    // which grow with the robot's mass; divided by the mass ratio squared, they weigh against the
    // state terms (squares of positions and velocities) as on the template robot.
    if (YAML::Node weights = c["weights"]) {
      for (const char* key : {"control", "friction"})
        if (weights[key])
          weights[key] = pyFloat(weights[key].as<double>() / (s.mass_ratio * s.mass_ratio));
    }
    if (YAML::Node safety = c["safety"]) {
      for (const char* key : {"hold_kp", "hold_kd"})
        if (safety[key])
          safety[key] =
              pyFloat(std::round(safety[key].as<double>() * s.mass_ratio * 1000.0) / 1000.0);
    }
    // policy_knots: one UDP datagram (messages/policy_t.lcm: x_ref, u_ff and K per knot), but at
    // least the kMinPolicyPeriods (6) tick periods the loader requires.
    const int template_knots = c["policy_knots"] ? c["policy_knots"].as<int>() : 8;
    const double per_knot = 8.0 * (s.nu + s.nu * 2.0 * s.nv + s.nq + s.nv);
    int knots = template_knots;
    while (knots > 2 && knots * per_knot + 128 > 60000.0) --knots;
    const int min_knots = static_cast<int>(std::ceil(6.0 / (rate * dt0) - 1e-9)) + 1;
    if (knots < min_knots) {
      s.notes.push_back("policy_knots " + std::to_string(min_knots) + ": " + std::to_string(knots) +
                        " would fit one 60 kB datagram (" + fmt(per_knot / 1000, 1) +
                        " kB per knot) but a policy must cover 6 tick "
                        "periods; LCM fragments the " +
                        fmt(min_knots * per_knot / 1000, 0) + " kB message");
      knots = min_knots;
    }
    knots = std::min(knots, first_knots);
    c["policy_knots"] = knots;
    s.policy_knots = knots;

    YAML::Emitter out;
    out << c;
    std::ofstream f(files[1]);
    f << header << "# Template: config/controller/" << s.template_name
      << ".yaml; gait phases, max_velocity scaled by sqrt(leg " << fmt(s.leg_length)
      << " m / template's) = " << fmt(s.ratio)
      << ", swing height and max body height by its square,\n"
      << "# min_normal_force and the hold gains by the mass ratio " << fmt(s.mass_ratio)
      << ", the control and friction weights by its inverse square.\n"
      << out.c_str() << "\n";
    if (!f) throw InitError("cannot write '" + files[1] + "'");
  }

  {  // the command script
    std::ofstream f(files[2]);
    f << header << "# Stand, step in place, forward, turn in place, stop and stand.\n"
      << "- {at: 0.0, gait: stand}\n"
      << "- {at: 1.0, gait: " << s.gait << "}\n"
      << "- {at: 3.5, vx: " << pyFloat(std::round(s.forward_speed * 100) / 100) << "}\n"
      << "- {at: 8.5, vx: 0.0, yaw_rate: " << pyFloat(std::round(s.turn_rate * 100) / 100) << "}\n"
      << "- {at: 12.5, yaw_rate: 0.0, gait: stand}\n";
    if (!f) throw InitError("cannot write '" + files[2] + "'");
  }
}

}  // namespace stride::init
