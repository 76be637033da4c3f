#include "tools/paper/astronaut.hpp"

#include <omp.h>

#include <cmath>

#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/residual_com.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"

namespace stride {

namespace {
Eigen::Matrix3d rotY(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
}

// Posture weights on x ⊖ x_ref: the base is free (its pose is the task, its velocity follows
// from the momentum), the joints are pulled towards the default posture.
Eigen::VectorXd postureWeights(const Model& model, double w_q, double w_v) {
  Eigen::VectorXd w = Eigen::VectorXd::Zero(2 * model.nv);
  w.segment(6, model.nv - 6).setConstant(w_q);
  w.tail(model.nv - 6).setConstant(w_v);
  return w;
}
}  // namespace

AstronautProblem::AstronautProblem(const Robot& robot, const AstronautOptions& options)
    : options_(options), locked_(lockJoints(robot, options.free_joints)) {
  Model& model = locked_.model;
  // Floating in space (§V-B): no gravity; an empty contact set gives the free-floating dynamics.
  model.gravity.setZero();
  const int nv = model.nv, nu = nv - 6, T = options.knots;
  x0_ = Eigen::VectorXd::Zero(model.nq + nv);
  x0_.head(model.nq) = locked_.default_q;
  x0_.head(3).setZero();

  // Waypoint i at knot round(i T / n) asks for Ry(i·turn/n).
  const double turn = options.turn_deg * M_PI / 180.0;
  for (int i = 1; i <= options.waypoints; ++i)
    waypoints_.emplace_back(static_cast<int>(std::lround(double(i) * T / options.waypoints)),
                            turn * i / options.waypoints);

  const ContactSet none;
  auto workspace = std::make_shared<SharedWorkspace>(model, std::max(omp_get_max_threads(), 2));
  std::vector<std::unique_ptr<ActionModel>> running;
  for (int k = 0; k < T; ++k) {
    auto knot = std::make_unique<KnotModel>(model, none, options.dt, workspace);
    CostModel& costs = knot->costs();
    costs.add("posture", std::make_unique<StateResidual>(model, nu, x0_),
              Activation::weightedQuadratic(
                  postureWeights(model, options.w_posture, options.w_joint_velocity)));
    costs.add("control", std::make_unique<ControlResidual>(model, nu), Activation::quadratic(nu),
              options.w_control);
    costs.add("momentum", std::make_unique<CentroidalMomentumResidual>(model, nu),
              Activation::quadratic(6), options.w_momentum);
    costs.add("limits", std::make_unique<JointLimitResidual>(model, nu),
              JointLimitResidual::activation(model, 1.0, options.limit_margin), options.w_limits);
    // Every knot carries the orientation term (one workspace slot for all); it is on only near
    // the waypoints before the terminal one.
    const int term = costs.add("orientation",
                               std::make_unique<FrameRotationResidual>(
                                   model, nu, options.base_frame, Eigen::Matrix3d::Identity()),
                               Activation::quadratic(3), options.w_orientation);
    costs[term].active = false;
    for (std::size_t i = 0; i + 1 < waypoints_.size(); ++i) {
      if (std::abs(k - waypoints_[i].first) > options.waypoint_width) continue;
      costs.residual<FrameRotationResidual>("orientation")
          ->setReference(rotY(waypoints_[i].second));
      costs[term].active = true;
    }
    running.push_back(std::move(knot));
  }
  auto terminal = std::make_unique<TerminalModel>(model);
  Eigen::VectorXd wT = postureWeights(model, options.w_posture, options.w_terminal_velocity);
  wT.segment(nv + 3, 3).setConstant(options.w_terminal_velocity);  // base angular velocity
  terminal->costs().add("posture", std::make_unique<StateResidual>(model, 0, x0_),
                        Activation::weightedQuadratic(wT));
  terminal->costs().add("limits", std::make_unique<JointLimitResidual>(model, 0),
                        JointLimitResidual::activation(model, 1.0, options.limit_margin),
                        options.w_limits);
  terminal->costs().add("orientation",
                        std::make_unique<FrameRotationResidual>(model, 0, options.base_frame,
                                                                rotY(waypoints_.back().second)),
                        Activation::quadratic(3), options.w_orientation);
  problem_ = std::make_unique<ShootingProblem>(x0_, std::move(running), std::move(terminal));
  problem_->setThreads(workspace->threads());
}

AstronautMotion analyzeMotion(const Model& model, const std::vector<Eigen::VectorXd>& xs, double dt,
                              const std::string& base_frame) {
  AstronautMotion m;
  Data data(model);
  const int base = model.getFrameId(base_frame);
  // The legs: the bodies each hip_pitch joint moves (its subtree). The hip yaw / roll links are
  // locked, so they are part of the base body and not counted.
  auto subtree = [&](const std::string& root) {
    std::vector<int> joints;
    if (!model.existJoint(root)) return joints;
    const int r = model.getJointId(root);
    for (int i = 1; i < model.njoints(); ++i)
      for (int j = i; j > 0; j = model.joints[j].parent)
        if (j == r) {
          joints.push_back(i);
          break;
        }
    return joints;
  };
  const std::vector<int> left = subtree("L_hip_pitch"), right = subtree("R_hip_pitch");
  auto legMomentum = [&](const std::vector<int>& joints, const Eigen::Vector3d& c) {
    Eigen::Vector3d h = Eigen::Vector3d::Zero();
    for (int i : joints) {
      // Body momentum in its joint frame, to world axes about the world origin, then about c.
      const Vector6d f = data.oMi[i].actForce(model.inertias[i] * data.v[i]);
      h += f.tail<3>() - c.cross(f.head<3>());
    }
    return h;
  };

  Eigen::Matrix3d R_prev = Eigen::Matrix3d::Identity();
  double pitch = 0.0, off = 0.0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const Eigen::VectorXd q = xs[k].head(model.nq), v = xs[k].tail(model.nv);
    const Vector6d hg = computeCentroidalMomentum(model, data, q, v);  // also forward kinematics
    const Eigen::Matrix3d R = updateFramePlacement(model, data, base).R;
    if (k > 0) {
      const Eigen::Vector3d w = log3(R * R_prev.transpose());  // world axes
      pitch += w.y();
      off += std::hypot(w.x(), w.z());
    }
    R_prev = R;
    m.t.push_back(dt * static_cast<double>(k));
    m.pitch.push_back(pitch);
    m.off_axis.push_back(off);
    m.h.push_back(hg.tail<3>());
    m.com.push_back(data.com);
    m.h_left.push_back(legMomentum(left, data.com));
    m.h_right.push_back(legMomentum(right, data.com));
    m.max_h = std::max(m.max_h, m.h.back().norm());
    m.max_h_leg = std::max({m.max_h_leg, m.h_left.back().norm(), m.h_right.back().norm()});
    m.max_com_drift = std::max(m.max_com_drift, (data.com - m.com.front()).norm());
  }
  return m;
}

FineCheck checkWithFinerSteps(const Model& model, const std::vector<Eigen::VectorXd>& xs,
                              const std::vector<Eigen::VectorXd>& us, double dt, int substeps,
                              const std::string& base_frame) {
  const KnotModel knot(model, ContactSet(), dt / substeps);
  auto kd = knot.createData();
  Data data(model);
  const int base = model.getFrameId(base_frame);
  auto momentum = [&](const Eigen::VectorXd& x) {
    return Eigen::Vector3d(
        computeCentroidalMomentum(model, data, x.head(model.nq), x.tail(model.nv)).tail<3>());
  };
  auto rotation = [&](const Eigen::VectorXd& x) {
    forwardKinematics(model, data, x.head(model.nq));
    return Eigen::Matrix3d(updateFramePlacement(model, data, base).R);
  };
  FineCheck c;
  for (std::size_t k = 0; k < us.size(); ++k) {
    Eigen::VectorXd x = xs[k];
    for (int s = 0; s < substeps; ++s) {
      knot.calc(*kd, x, us[k]);
      x = kd->x_next;
    }
    const Eigen::Vector3d h0 = momentum(xs[k]);
    c.max_dh_plan = std::max(c.max_dh_plan, (momentum(xs[k + 1]) - h0).norm());
    c.max_dh_fine = std::max(c.max_dh_fine, (momentum(x) - h0).norm());
    c.pitch += log3(rotation(x) * rotation(xs[k]).transpose()).y();
  }
  return c;
}

}  // namespace stride
