#pragma once
// Robots and scenes shared by the sim tests: the in-house robots from config/robots, and a "sled"
// (one rigid box on four corner points) whose sliding has a closed-form answer.

#include <string>

#include "config/robot_config.hpp"
#include "sim/policy.hpp"
#include "sim/simulator.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"

namespace stride::sim_test {

inline const Robot& robot(const std::string& name) {
  static const Robot quad =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  static const Robot humanoid =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml");
  return name == "stride_quad" ? quad : humanoid;
}

// Joint PD gains that hold each robot's default posture (scaled to its size), capped per joint for
// the 1 ms step: uncapped, the quad's light shanks (and the humanoid's forearms) oscillate step to
// step in flight.
inline sim::HoldPolicy holdDefault(const Robot& r) {
  return r.name == "stride_quad" ? sim::HoldPolicy(r.model, r.default_q, 100.0, 2.0, 1e-3)
                                 : sim::HoldPolicy(r.model, r.default_q, 3000.0, 30.0, 1e-3);
}

// A 1 kg box, 0.2 x 0.2 x 0.1 m, centre of mass at the base origin, touching the ground by its
// four bottom corners.
struct Sled {
  static constexpr double kMass = 1.0, kHalfX = 0.1, kHalfY = 0.1, kHalfZ = 0.05;
  Model model;
  std::vector<sim::ContactPoint> points;
  Sled() {
    const int j = model.addJoint(0, JointType::FreeFlyer, SE3::Identity(), "root");
    const double a = 2 * kHalfX, b = 2 * kHalfY, c = 2 * kHalfZ;
    const Eigen::Vector3d I(kMass / 12 * (b * b + c * c), kMass / 12 * (a * a + c * c),
                            kMass / 12 * (a * a + b * b));
    model.appendBodyToJoint(
        j, Inertia::FromMassComInertia(kMass, Eigen::Vector3d::Zero(), I.asDiagonal()));
    const int frame = model.getFrameId("root");
    for (double sx : {1.0, -1.0})
      for (double sy : {1.0, -1.0})
        points.push_back({"corner", frame, Eigen::Vector3d(sx * kHalfX, sy * kHalfY, -kHalfZ), 0});
  }
  // Resting on the ground at the origin.
  Eigen::VectorXd restingQ() const {
    Eigen::VectorXd q(7);
    q << 0, 0, kHalfZ, 0, 0, 0, 1;
    return q;
  }
};

// World velocity of a frame's origin.
inline Eigen::Vector3d frameVelocity(const Model& model, Data& data, int frame,
                                     const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  forwardKinematics(model, data, q, v);
  return getFrameVelocity(model, data, frame, ReferenceFrame::LocalWorldAligned).head<3>();
}

}  // namespace stride::sim_test
