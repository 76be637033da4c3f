#include "config/robot_config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "solver/multibody/lie_group.hpp"

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
}  // namespace

Robot loadRobot(const std::string& yaml_path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::BadFile&) {
    fail(yaml_path, "file does not exist or cannot be read");
  } catch (const YAML::Exception& e) {
    fail(yaml_path, std::string("malformed YAML: ") + e.what());
  }
  if (!root.IsMap()) fail(yaml_path, "the top level must be a mapping");
  Robot robot;
  robot.yaml_path = yaml_path;
  try {
    robot.name = need(root, "name", yaml_path).as<std::string>();
    const std::filesystem::path urdf = std::filesystem::path(yaml_path).parent_path() /
                                       need(root, "urdf", yaml_path).as<std::string>();
    robot.urdf_path = urdf.string();
    const std::string root_joint = need(root, "root_joint", yaml_path).as<std::string>();
    if (root_joint != "free-flyer" && root_joint != "fixed")
      fail(yaml_path, "root_joint must be 'free-flyer' or 'fixed', not '" + root_joint + "'");
    robot.model = buildModelFromUrdf(
        robot.urdf_path, root_joint == "fixed" ? RootJoint::Fixed : RootJoint::FreeFlyer);
    Model& model = robot.model;

    for (const auto& c : need(root, "contacts", yaml_path)) {
      ContactSpec spec{need(c, "frame", yaml_path).as<std::string>(),
                       need(c, "dim", yaml_path).as<int>()};
      if (!model.existFrame(spec.frame))
        fail(yaml_path, "contact frame '" + spec.frame + "' is not in the URDF");
      if (spec.dim != 3 && spec.dim != 6)
        fail(yaml_path,
             "contact '" + spec.frame + "' has dim " + std::to_string(spec.dim) + " (3 or 6)");
      robot.contacts.push_back(spec);
    }
    if (root["sole_half_extents"]) {
      const auto e = root["sole_half_extents"].as<std::vector<double>>();
      if (e.size() != 2 || !(e[0] > 0) || !(e[1] > 0))
        fail(yaml_path, "sole_half_extents must be two positive numbers");
      robot.sole_half_extents << e[0], e[1];
    }

    // Every actuated joint needs a torque limit and a default angle: a missing one is an error,
    // not a silent zero.
    const YAML::Node limits = need(root, "torque_limits", yaml_path);
    const YAML::Node posture = need(root, "default_posture", yaml_path);
    const YAML::Node joints = need(posture, "joints", yaml_path);
    for (const auto& table : {limits, joints})
      for (const auto& kv : table)
        if (!model.existJoint(kv.first.as<std::string>()))
          fail(yaml_path, "joint '" + kv.first.as<std::string>() + "' is not in the URDF");
    robot.default_q = neutral(model);
    for (int i = 1; i < model.njoints(); ++i) {
      const Joint& j = model.joints[i];
      if (j.type == JointType::FreeFlyer) continue;
      if (!limits[j.name]) fail(yaml_path, "torque_limits has no entry for joint '" + j.name + "'");
      if (!joints[j.name])
        fail(yaml_path, "default_posture.joints has no entry for joint '" + j.name + "'");
      const double limit = limits[j.name].as<double>();
      if (!(limit > 0) || !std::isfinite(limit))
        fail(yaml_path, "torque limit of '" + j.name + "' must be positive");
      model.effortLimit[j.idx_v] = limit;
      robot.default_q[j.idx_q] = joints[j.name].as<double>();
    }
    if (model.hasFreeFlyer()) {
      const auto base = need(posture, "base", yaml_path).as<std::vector<double>>();
      if (base.size() != 7)
        fail(yaml_path, "default_posture.base needs 7 numbers [x y z qx qy qz qw]");
      for (int k = 0; k < 7; ++k) robot.default_q[k] = base[k];
      const double n = robot.default_q.segment<4>(3).norm();
      if (std::abs(n - 1.0) > 1e-6) fail(yaml_path, "default_posture.base quaternion is not unit");
      normalize(model, robot.default_q);
    }
    if (!robot.default_q.allFinite()) fail(yaml_path, "default_posture has non-finite values");
    model.referenceConfigurations["default"] = robot.default_q;
  } catch (const YAML::Exception& e) {
    fail(yaml_path, std::string("bad value: ") + e.what());
  } catch (const UrdfError& e) {
    fail(yaml_path, e.what());
  }
  return robot;
}

}  // namespace stride
