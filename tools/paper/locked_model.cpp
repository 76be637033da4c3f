#include "tools/paper/locked_model.hpp"

#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <memory>
#include <stdexcept>

namespace stride {

std::string lockJointsInUrdf(const std::string& urdf_path,
                             const std::map<std::string, double>& locked) {
  urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDFFile(urdf_path);
  if (!urdf) throw UrdfError("URDF '" + urdf_path + "': cannot be parsed");
  for (const auto& [name, angle] : locked) {
    const auto it = urdf->joints_.find(name);
    if (it == urdf->joints_.end())
      throw std::invalid_argument("lockJointsInUrdf: no joint '" + name + "' in " + urdf_path);
    urdf::Joint& joint = *it->second;
    const Eigen::Vector3d axis(joint.axis.x, joint.axis.y, joint.axis.z);
    urdf::Pose& origin = joint.parent_to_joint_origin_transform;
    const Eigen::Quaterniond r0(origin.rotation.w, origin.rotation.x, origin.rotation.y,
                                origin.rotation.z);
    if (joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::CONTINUOUS) {
      // parent → joint frame at q: origin · Rot(axis, q); the rotation keeps the origin's point.
      const Eigen::Quaterniond r = (r0 * Eigen::AngleAxisd(angle, axis.normalized())).normalized();
      origin.rotation.setFromQuaternion(r.x(), r.y(), r.z(), r.w());
    } else if (joint.type == urdf::Joint::PRISMATIC) {
      const Eigen::Vector3d p =
          Eigen::Vector3d(origin.position.x, origin.position.y, origin.position.z) +
          r0 * (angle * axis.normalized());
      origin.position = urdf::Vector3(p.x(), p.y(), p.z());
    } else if (joint.type != urdf::Joint::FIXED) {
      throw std::invalid_argument("lockJointsInUrdf: joint '" + name +
                                  "' is not revolute, continuous or prismatic");
    }
    joint.type = urdf::Joint::FIXED;
    joint.limits.reset();
    joint.dynamics.reset();
    joint.safety.reset();
    joint.calibration.reset();
    joint.mimic.reset();
  }
  std::unique_ptr<TiXmlDocument> doc(urdf::exportURDF(*urdf));
  TiXmlPrinter printer;
  doc->Accept(&printer);
  return printer.CStr();
}

LockedRobot lockJoints(const Robot& robot, const std::vector<std::string>& free_joints) {
  const Model& full = robot.model;
  for (const auto& name : free_joints)
    if (!full.existJoint(name))
      throw std::invalid_argument("lockJoints: no joint '" + name + "' in " + robot.urdf_path);
  std::map<std::string, double> locked;
  for (int i = 1; i < full.njoints(); ++i) {
    const Joint& j = full.joints[i];
    if (j.type != JointType::Revolute && j.type != JointType::Prismatic) continue;
    bool keep = false;
    for (const auto& name : free_joints) keep = keep || name == j.name;
    if (!keep) locked[j.name] = robot.default_q[j.idx_q];
  }
  LockedRobot out;
  const RootJoint root = full.hasFreeFlyer() ? RootJoint::FreeFlyer : RootJoint::Fixed;
  out.model = buildModelFromUrdfString(lockJointsInUrdf(robot.urdf_path, locked), root,
                                       robot.urdf_path + " (locked)");
  out.model.name = full.name;
  for (int i = 1; i < out.model.njoints(); ++i)
    if (out.model.joints[i].type != JointType::FreeFlyer)
      out.free.push_back(out.model.joints[i].name);
  out.default_q = reduceConfiguration(full, out.model, robot.default_q);
  // The robot's torque limits (YAML) replace the URDF efforts, as loadRobot does.
  for (const auto& name : out.free) {
    const Joint& jr = out.model.joints[out.model.getJointId(name)];
    const Joint& jf = full.joints[full.getJointId(name)];
    out.model.effortLimit[jr.idx_v] = full.effortLimit[jf.idx_v];
  }
  return out;
}

namespace {
// The entries of the joints the reduced model kept, by joint name: configuration (idx_q, nq) or
// velocity (idx_v, nv) coordinates.
Eigen::VectorXd keepJoints(const Model& full, const Model& reduced, const Eigen::VectorXd& x_full,
                           bool configuration) {
  Eigen::VectorXd x(configuration ? reduced.nq : reduced.nv);
  for (int i = 1; i < reduced.njoints(); ++i) {
    const Joint& jr = reduced.joints[i];
    const Joint& jf = full.joints[full.getJointId(jr.name)];
    if (configuration)
      x.segment(jr.idx_q, jr.nq) = x_full.segment(jf.idx_q, jf.nq);
    else
      x.segment(jr.idx_v, jr.nv) = x_full.segment(jf.idx_v, jf.nv);
  }
  return x;
}
}  // namespace

Eigen::VectorXd reduceConfiguration(const Model& full, const Model& reduced,
                                    const Eigen::VectorXd& q_full) {
  return keepJoints(full, reduced, q_full, true);
}

Eigen::VectorXd reduceVelocity(const Model& full, const Model& reduced,
                               const Eigen::VectorXd& v_full) {
  return keepJoints(full, reduced, v_full, false);
}

Eigen::VectorXd expandConfiguration(const Model& full, const Model& reduced,
                                    const Eigen::VectorXd& q_reduced,
                                    const Eigen::VectorXd& q_locked) {
  Eigen::VectorXd q = q_locked;
  for (int i = 1; i < reduced.njoints(); ++i) {
    const Joint& jr = reduced.joints[i];
    const Joint& jf = full.joints[full.getJointId(jr.name)];
    q.segment(jf.idx_q, jf.nq) = q_reduced.segment(jr.idx_q, jr.nq);
  }
  return q;
}

Eigen::VectorXd expandVelocity(const Model& full, const Model& reduced,
                               const Eigen::VectorXd& v_reduced) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(full.nv);
  for (int i = 1; i < reduced.njoints(); ++i) {
    const Joint& jr = reduced.joints[i];
    const Joint& jf = full.joints[full.getJointId(jr.name)];
    v.segment(jf.idx_v, jf.nv) = v_reduced.segment(jr.idx_v, jr.nv);
  }
  return v;
}

}  // namespace stride
