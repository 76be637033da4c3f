#pragma once
// Helpers shared by the multibody property tests:
//  - makeRandomTree: random kinematic trees of many shapes, built with the Model builder API;
//  - standardRobots: the reference robots (URDF and in-house YAML);
//  - central finite differences on the configuration manifold (tangent-space columns,
//    column j = d/de f(q ⊕ e e_j)), and a few small numeric utilities;
//  - the dynamics identities checked by both test_dynamics and test_random_trees
//    (namespace stride::checks), so that the two suites check exactly the same things.
// Header-only.

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "config/robot_config.hpp"
#include "solver/multibody/aba.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/data.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/model.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {

namespace random_tree_detail {

inline double uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

inline int uniformInt(std::mt19937& rng, int lo, int hi) {
  return std::uniform_int_distribution<int>(lo, hi)(rng);
}

inline Eigen::Vector3d randomUnitVector(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  for (;;) {
    const Eigen::Vector3d a(n(rng), n(rng), n(rng));
    if (a.norm() > 1e-3) return a.normalized();
  }
}

// exp of a random rotation vector (uniform direction, angle up to pi), via Eigen's angle-axis so
// that the trees do not depend on the library's own exp3.
inline Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  const Eigen::Vector3d axis = randomUnitVector(rng);
  return Eigen::AngleAxisd(uniform(rng, 0.0, M_PI), axis).toRotationMatrix();
}

inline SE3 randomPlacement(std::mt19937& rng, double max_translation) {
  return SE3(randomRotation(rng), uniform(rng, 0.0, max_translation) * randomUnitVector(rng));
}

// A physically valid body: mass 0.1..5 kg, centre of mass up to 0.1 m from the origin, principal
// moments from random second moments of the mass distribution (so they satisfy the triangle
// inequality, e.g. Ixx = Syy + Szz), random principal axes.
inline Inertia randomInertia(std::mt19937& rng) {
  const double mass = uniform(rng, 0.1, 5.0);
  const Eigen::Vector3d com = uniform(rng, 0.0, 0.1) * randomUnitVector(rng);
  const Eigen::Vector3d S(mass * uniform(rng, 1e-3, 2e-2), mass * uniform(rng, 1e-3, 2e-2),
                          mass * uniform(rng, 1e-3, 2e-2));
  const Eigen::Vector3d principal(S.y() + S.z(), S.x() + S.z(), S.x() + S.y());
  const Eigen::Matrix3d axes = randomRotation(rng);
  const Eigen::Matrix3d Ic = axes * principal.asDiagonal() * axes.transpose();
  return Inertia::FromMassComInertia(mass, com, Ic);
}

}  // namespace random_tree_detail

// A random tree of n_joints one-dof joints (plus a free-flyer root named "root_joint" when
// free_flyer is set, which then carries every other joint). Each tree draws its own "chain bias"
// so that seeds give chains, stars and everything between; parents always have smaller indices.
// Joints: revolute about +x/+y/+z exactly (the aligned fast paths), revolute about a random unit
// axis (or -x/-y/-z), prismatic along a random or aligned axis. Position limits always contain 0
// (so neutral() is admissible); some revolute joints are continuous. Every joint carries a body,
// sometimes at a non-identity placement, sometimes with a second body merged as a fixed link would
// be. A few Operational frames hang from random joints (the universe included) at random
// placements.
inline Model makeRandomTree(std::mt19937& rng, int n_joints, bool free_flyer) {
  using namespace random_tree_detail;
  Model model;
  model.name = "random_tree";
  int first_parent = 0;
  if (free_flyer) {
    const int root = model.addJoint(0, JointType::FreeFlyer, SE3::Identity(), "root_joint");
    model.appendBodyToJoint(root, randomInertia(rng),
                            uniform(rng, 0, 1) < 0.5 ? randomPlacement(rng, 0.1) : SE3::Identity());
    first_parent = root;
  }
  const double chain_bias = uniform(rng, 0.0, 1.0);
  for (int k = 0; k < n_joints; ++k) {
    // Joints are added in depth-first order (Model::addJoint): the parent is the last joint added
    // or one of its ancestors, down to the root (the free-flyer, else the universe). Every tree
    // has such an order, so drawing uniformly on that path still reaches every shape.
    std::vector<int> path;
    for (int a = model.njoints() - 1; a >= first_parent; a = model.joints[a].parent) {
      path.push_back(a);
      if (a == 0) break;
    }
    const int parent = uniform(rng, 0, 1) < chain_bias
                           ? path.front()
                           : path[uniformInt(rng, 0, static_cast<int>(path.size()) - 1)];

    JointType type = JointType::Revolute;
    Eigen::Vector3d axis;
    const double draw = uniform(rng, 0, 1);
    if (draw < 0.35) {
      axis = Eigen::Vector3d::Unit(uniformInt(rng, 0, 2));  // exactly +x, +y or +z
    } else if (draw < 0.75) {
      if (uniform(rng, 0, 1) < 0.2)
        axis = -Eigen::Vector3d::Unit(uniformInt(rng, 0, 2));
      else
        axis = randomUnitVector(rng);
    } else {
      type = JointType::Prismatic;
      axis = uniform(rng, 0, 1) < 0.3
                 ? Eigen::Vector3d(Eigen::Vector3d::Unit(uniformInt(rng, 0, 2)))
                 : randomUnitVector(rng);
    }
    const std::string name = "joint_" + std::to_string(k);
    const int id = model.addJoint(parent, type, randomPlacement(rng, 0.3), name, axis);

    if (type == JointType::Prismatic) {
      model.setJointLimits(id, -uniform(rng, 0.02, 0.3), uniform(rng, 0.02, 0.3),
                           uniform(rng, 0.5, 5.0), uniform(rng, 10.0, 200.0));
    } else if (uniform(rng, 0, 1) < 0.75) {
      model.setJointLimits(id, -uniform(rng, 0.1, 3.0), uniform(rng, 0.1, 3.0),
                           uniform(rng, 1.0, 20.0), uniform(rng, 1.0, 200.0));
    }  // else: continuous revolute joint, no position limit

    const bool offset_body = uniform(rng, 0, 1) < 0.35;
    const SE3 body_placement = offset_body ? randomPlacement(rng, 0.2) : SE3::Identity();
    model.appendBodyToJoint(id, randomInertia(rng), body_placement);
    if (offset_body) {
      Frame body;
      body.name = "body_" + std::to_string(k);
      body.type = FrameType::Body;
      body.parentJoint = id;
      body.parentFrame = model.getFrameId(name);
      body.placement = body_placement;
      model.addFrame(body);
    }
    if (uniform(rng, 0, 1) < 0.25)  // a link merged through a fixed joint
      model.appendBodyToJoint(id, randomInertia(rng), randomPlacement(rng, 0.3));
  }

  const int n_frames = 1 + n_joints / 4;
  for (int k = 0; k < n_frames; ++k) {
    Frame f;
    f.name = "op_frame_" + std::to_string(k);
    f.type = FrameType::Operational;
    f.parentJoint = uniformInt(rng, 0, model.njoints() - 1);
    f.parentFrame =
        uniform(rng, 0, 1) < 0.5 ? model.getFrameId(model.joints[f.parentJoint].name) : 0;
    f.placement = randomPlacement(rng, 0.3);
    model.addFrame(f);
  }
  return model;
}

struct RobotCase {
  std::string name;
  Model model;
};

// solo12, talos_reduced, ur5 (fixed base) and the in-house stride_quad and stride_humanoid.
// Loaded once per process; returns a copy.
inline std::vector<RobotCase> standardRobots() {
  static const std::vector<RobotCase> robots = [] {
    std::vector<RobotCase> r;
    r.push_back({"solo12", buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/solo12/solo12.urdf",
                                              RootJoint::FreeFlyer)});
    r.push_back(
        {"talos_reduced", buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/talos/talos_reduced.urdf",
                                             RootJoint::FreeFlyer)});
    r.push_back({"ur5", buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/ur5/ur5_robot.urdf",
                                           RootJoint::Fixed)});
    r.push_back(
        {"stride_quad", loadRobot(STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml").model});
    r.push_back(
        {"stride_humanoid",
         loadRobot(STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml").model});
    return r;
  }();
  return robots;
}

// ---- finite differences on the configuration manifold ----

// For every tangent direction j: visit(j, q ⊕ h e_j, q ⊕ -h e_j).
template <typename Visit>
void forEachTangentDirection(const Model& model, const Eigen::VectorXd& q, double h,
                             Visit&& visit) {
  Eigen::VectorXd dv = Eigen::VectorXd::Zero(model.nv);
  Eigen::VectorXd q_plus(model.nq), q_minus(model.nq);
  for (int j = 0; j < model.nv; ++j) {
    dv[j] = h;
    integrate(model, q, dv, q_plus);
    dv[j] = -h;
    integrate(model, q, dv, q_minus);
    dv[j] = 0.0;
    visit(j, q_plus, q_minus);
  }
}

// Central-difference Jacobian (rows = size of f, nv columns) of a vector-valued f(q):
// column j = (f(q ⊕ h e_j) - f(q ⊕ -h e_j)) / 2h.
template <typename F>
Eigen::MatrixXd manifoldCentralDifference(const Model& model, const Eigen::VectorXd& q, F&& f,
                                          double h = 1e-6) {
  Eigen::MatrixXd J;
  forEachTangentDirection(model, q, h,
                          [&](int j, const Eigen::VectorXd& qp, const Eigen::VectorXd& qm) {
                            const Eigen::VectorXd fp = f(qp), fm = f(qm);
                            if (J.size() == 0) J.resize(fp.size(), model.nv);
                            J.col(j) = (fp - fm) / (2.0 * h);
                          });
  return J;
}

// Central difference of a placement in its own (LOCAL) tangent space:
// (log6(M0^-1 M+) - log6(M0^-1 M-)) / 2h.
inline Vector6d localPlacementDerivative(const SE3& M0, const SE3& M_plus, const SE3& M_minus,
                                         double h) {
  return (log6(M0.actInv(M_plus)) - log6(M0.actInv(M_minus))) / (2.0 * h);
}

// A LOCAL motion (d/de log6(M0^-1 M(e))) expressed in the other reference frames.
inline Vector6d expressLocal(const SE3& M0, const Vector6d& local, ReferenceFrame rf) {
  switch (rf) {
    case ReferenceFrame::Local:
      return local;
    case ReferenceFrame::World:
      return M0.act(local);
    case ReferenceFrame::LocalWorldAligned: {
      Vector6d r;
      r.head<3>() = M0.R * local.head<3>();  // the origin's velocity, world axes
      r.tail<3>() = M0.R * local.tail<3>();
      return r;
    }
  }
  return local;
}

// Finite-difference Jacobians (6 x nv) of every frame (frames = true) or every joint placement
// (frames = false), in the reference frame rf. result[i] belongs to frame / joint i.
inline std::vector<Matrix6Xd> placementJacobiansFD(const Model& model, const Eigen::VectorXd& q,
                                                   bool frames, ReferenceFrame rf,
                                                   double h = 1e-6) {
  Data d0(model), dp(model), dm(model);
  framesForwardKinematics(model, d0, q);
  const std::vector<SE3>& M0 = frames ? d0.oMf : d0.oMi;
  std::vector<Matrix6Xd> J(M0.size(), Matrix6Xd::Zero(6, model.nv));
  forEachTangentDirection(
      model, q, h, [&](int j, const Eigen::VectorXd& qp, const Eigen::VectorXd& qm) {
        framesForwardKinematics(model, dp, qp);
        framesForwardKinematics(model, dm, qm);
        const std::vector<SE3>& Mp = frames ? dp.oMf : dp.oMi;
        const std::vector<SE3>& Mm = frames ? dm.oMf : dm.oMi;
        for (size_t i = 0; i < M0.size(); ++i) {
          // LOCAL: d/de log6(M0^-1 M(e)); WORLD: the same motion seen from the world origin;
          // LOCAL_WORLD_ALIGNED: d/de of the origin's translation, LOCAL angular rotated by R.
          const Vector6d local = localPlacementDerivative(M0[i], Mp[i], Mm[i], h);
          if (rf == ReferenceFrame::LocalWorldAligned) {
            J[i].col(j).head<3>() = (Mp[i].p - Mm[i].p) / (2.0 * h);
            J[i].col(j).tail<3>() = M0[i].R * local.tail<3>();
          } else {
            J[i].col(j) = expressLocal(M0[i], local, rf);
          }
        }
      });
  return J;
}

// ---- small numeric utilities ----

// |a - b| / max(1, |b|) in the Frobenius norm: relative for large quantities, absolute near zero.
template <typename A, typename B>
double relativeError(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  return (a - b).norm() / std::max(1.0, b.norm());
}

// Uniform in [-scale, scale]^n.
inline Eigen::VectorXd randomVector(std::mt19937& rng, int n, double scale = 1.0) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd x(n);
  for (int k = 0; k < n; ++k) x[k] = u(rng);
  return x;
}

// Kinetic energy summed body by body from data.v (forwardKinematics(q, v) first).
inline double kineticEnergyFromBodies(const Model& model, const Data& data) {
  double e = 0.0;
  for (int i = 1; i < model.njoints(); ++i) e += model.inertias[i].kineticEnergy(data.v[i]);
  return e;
}

// ---- dynamics identities (gtest assertions), shared by test_dynamics and test_random_trees ----

namespace checks {

// Tolerances: exact identities between two algorithms, and comparisons with central finite
// differences (step kFdStep, truncation and rounding errors both ~1e-10 relative).
constexpr double kExact = 1e-9;
constexpr double kFd = 1e-6;
constexpr double kFdStep = 1e-6;

// A random state: q uniform in the limits, v and a ~ U(-1, 1), tau ~ U(-5, 5).
struct Sample {
  Eigen::VectorXd q, v, a, tau;
};

inline std::vector<Sample> randomSamples(const Model& model, std::mt19937& rng, int n) {
  std::vector<Sample> out;
  for (int k = 0; k < n; ++k)
    out.push_back({randomConfiguration(model, rng), randomVector(rng, model.nv),
                   randomVector(rng, model.nv), randomVector(rng, model.nv, 5.0)});
  return out;
}

// ABA equals M^-1 (tau - b), with M from CRBA and b from RNEA.
inline void abaMatchesCrbaSolve(const Model& model, const Sample& s) {
  Data data(model);
  const Eigen::VectorXd ddq = aba(model, data, s.q, s.v, s.tau);
  const Eigen::MatrixXd M = crba(model, data, s.q);
  const Eigen::VectorXd b = nonLinearEffects(model, data, s.q, s.v);
  const Eigen::VectorXd ref = M.llt().solve(s.tau - b);
  EXPECT_LT(relativeError(ddq, ref), kExact)
      << "aba " << ddq.transpose() << "\n ref " << ref.transpose();
  // And the inverse problem: rnea(q, v, aba(q, v, tau)) = tau.
  EXPECT_LT(relativeError(Eigen::VectorXd(rnea(model, data, s.q, s.v, ddq)), s.tau), kExact);
}

// RNEA equals M a + b; g = rnea(q, 0, 0); b = rnea(q, v, 0).
inline void rneaMatchesMassMatrixAndBias(const Model& model, const Sample& s) {
  Data data(model);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.nv);
  const Eigen::VectorXd tau = rnea(model, data, s.q, s.v, s.a);
  const Eigen::MatrixXd M = crba(model, data, s.q);
  const Eigen::VectorXd b = nonLinearEffects(model, data, s.q, s.v);
  const Eigen::VectorXd g = computeGeneralizedGravity(model, data, s.q);
  EXPECT_LT(relativeError(tau, Eigen::VectorXd(M * s.a + b)), kExact);
  EXPECT_LT(relativeError(g, Eigen::VectorXd(rnea(model, data, s.q, zero, zero))), 1e-12);
  EXPECT_LT(relativeError(b, Eigen::VectorXd(rnea(model, data, s.q, s.v, zero))), 1e-12);
  // Column j of M is the torque of a unit acceleration without velocity and gravity terms.
  Model no_gravity = model;
  no_gravity.gravity.setZero();
  Data d0(no_gravity);
  Eigen::MatrixXd M_rnea(model.nv, model.nv);
  for (int j = 0; j < model.nv; ++j)
    M_rnea.col(j) = rnea(no_gravity, d0, s.q, zero, Eigen::VectorXd::Unit(model.nv, j));
  EXPECT_LT(relativeError(M_rnea, M), kExact);
  // Independent of the RNEA sweeps: gravity torques are the gradient of the potential energy,
  // g = -m Jcom^T gravity, and the velocity terms follow from the kinetic energy alone
  // (Lagrange / Euler-Poincare equations with the base velocity in the base frame):
  //   b - g = d/dt (M v) + [v_base x* (M v)_base; 0] - 1/2 grad_q (v^T M v),
  // d/dt along q ⊕ t v (whose velocity stays v), grad_q in the tangent space, both by central
  // differences. Gyroscopic forces do no work, so this sees errors v^T (b - g) cannot.
  Data dc(model);
  const Eigen::Matrix3Xd Jcom = jacobianCenterOfMass(model, dc, s.q);
  EXPECT_LT(relativeError(g, Eigen::VectorXd(-dc.mass * Jcom.transpose() * model.gravity)), kExact);
  const double h = kFdStep;
  const Eigen::MatrixXd M_plus = crba(model, dc, integrate(model, s.q, h * s.v));
  const Eigen::MatrixXd M_minus = crba(model, dc, integrate(model, s.q, -h * s.v));
  Eigen::VectorXd lagrange = (M_plus - M_minus) * s.v / (2.0 * h);
  if (model.hasFreeFlyer()) {
    const Vector6d momentum = (M * s.v).head<6>();
    lagrange.head<6>() += forceCross(s.v.head<6>(), momentum);
  }
  lagrange -= manifoldCentralDifference(
                  model, s.q,
                  [&](const Eigen::VectorXd& q) {
                    return Eigen::VectorXd::Constant(1, 0.5 * s.v.dot(crba(model, dc, q) * s.v));
                  },
                  h)
                  .transpose();
  EXPECT_LT(relativeError(Eigen::VectorXd(b - g), lagrange), kFd)
      << "b - g    " << (b - g).transpose() << "\n lagrange " << lagrange.transpose();
}

// M symmetric positive definite, and 1/2 v^T M v equals the bodies' kinetic energy.
inline void massMatrixIsSpdAndGivesKineticEnergy(const Model& model, const Sample& s) {
  Data data(model);
  const Eigen::MatrixXd M = crba(model, data, s.q);
  EXPECT_LE((M - M.transpose()).norm(), 1e-12 * M.norm());
  EXPECT_EQ(M.llt().info(), Eigen::Success);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  forwardKinematics(model, data, s.q, s.v);
  const double T = kineticEnergyFromBodies(model, data);
  EXPECT_GT(T, 0.0);
  EXPECT_NEAR(0.5 * s.v.dot(M * s.v), T, kExact * std::max(1.0, T));
}

// Jacobians of every frame (frames = true) or joint against finite differences of placements,
// in the three reference frames, and J v against the velocities from forwardKinematics(q, v).
inline void placementJacobiansMatchFiniteDifferences(const Model& model, const Sample& s,
                                                     bool frames) {
  const ReferenceFrame rfs[] = {ReferenceFrame::Local, ReferenceFrame::World,
                                ReferenceFrame::LocalWorldAligned};
  const char* rf_names[] = {"LOCAL", "WORLD", "LOCAL_WORLD_ALIGNED"};
  Data data(model), dv(model);
  computeJointJacobians(model, data, s.q);
  updateFramePlacements(model, data);
  forwardKinematics(model, dv, s.q, s.v);
  const int n = frames ? model.nframes() : model.njoints();
  Matrix6Xd J(6, model.nv);
  for (int r = 0; r < 3; ++r) {
    const std::vector<Matrix6Xd> fd = placementJacobiansFD(model, s.q, frames, rfs[r], kFdStep);
    for (int i = 0; i < n; ++i) {
      const std::string what = std::string(frames ? "frame " : "joint ") +
                               (frames ? model.frames[i].name : model.joints[i].name) + " in " +
                               rf_names[r];
      J.setConstant(7.0);  // every entry must be written
      Vector6d vel;
      if (frames) {
        getFrameJacobian(model, data, i, rfs[r], J);
        vel = getFrameVelocity(model, dv, i, rfs[r]);
      } else {
        getJointJacobian(model, data, i, rfs[r], J);
        vel = expressLocal(dv.oMi[i], dv.v[i], rfs[r]);
      }
      EXPECT_LT(relativeError(J, fd[i]), kFd) << what << "\nJ =\n" << J << "\nfd =\n" << fd[i];
      EXPECT_LT(relativeError(Vector6d(J * s.v), vel), kExact) << what;
    }
  }
}

// The trajectory q(t) = q ⊕ xi(t), xi(t) = t v + t^2/2 a, has velocity
// v(t) = dIntegrate(q, xi(t), Second) (v + t a), so v(0) = v and (because ad(v) v = 0)
// v'(0) = a exactly, on a free-flyer too.
inline void stateAlongTrajectory(const Model& model, const Sample& s, double t, Eigen::VectorXd& q,
                                 Eigen::VectorXd& v) {
  const Eigen::VectorXd xi = t * s.v + 0.5 * t * t * s.a;
  q = integrate(model, s.q, xi);
  Eigen::MatrixXd Jv(model.nv, model.nv);
  dIntegrate(model, s.q, xi, Jv, ArgumentPosition::Second);
  v = Jv * (s.v + t * s.a);
}

// Frame accelerations after forwardKinematics(q, v, a) against time derivatives of frame
// velocities along that trajectory: spatial acceleration in LOCAL and WORLD is d/dt of the
// velocity in the same frame; the classical acceleration (LOCAL_WORLD_ALIGNED) is d/dt of the
// world-aligned velocity of the frame origin, R (a_lin + w x v_lin).
inline void frameAccelerationsMatchTimeDerivatives(const Model& model, const Sample& s) {
  const double h = 1e-5;
  Data data(model), dp(model), dm(model);
  forwardKinematics(model, data, s.q, s.v, s.a);
  Eigen::VectorXd qp, vp, qm, vm;
  stateAlongTrajectory(model, s, h, qp, vp);
  stateAlongTrajectory(model, s, -h, qm, vm);
  forwardKinematics(model, dp, qp, vp);
  forwardKinematics(model, dm, qm, vm);
  for (int f = 0; f < model.nframes(); ++f) {
    SCOPED_TRACE("frame " + model.frames[f].name);
    for (ReferenceFrame rf : {ReferenceFrame::Local, ReferenceFrame::World}) {
      const Vector6d fd =
          (getFrameVelocity(model, dp, f, rf) - getFrameVelocity(model, dm, f, rf)) / (2 * h);
      EXPECT_LT(relativeError(getFrameAcceleration(model, data, f, rf), fd), kFd)
          << "spatial acceleration, reference frame " << static_cast<int>(rf);
    }
    const Vector6d fd = (getFrameVelocity(model, dp, f, ReferenceFrame::LocalWorldAligned) -
                         getFrameVelocity(model, dm, f, ReferenceFrame::LocalWorldAligned)) /
                        (2 * h);
    const Vector6d classical =
        getFrameClassicalAcceleration(model, data, f, ReferenceFrame::LocalWorldAligned);
    EXPECT_LT(relativeError(classical, fd), kFd) << "classical acceleration\n"
                                                 << classical.transpose() << "\n"
                                                 << fd.transpose();
    // LOCAL is the same vector in the frame's axes.
    const Eigen::Matrix3d R = (data.oMi[model.frames[f].parentJoint] * model.frames[f].placement).R;
    const Vector6d local = getFrameClassicalAcceleration(model, data, f, ReferenceFrame::Local);
    Vector6d rotated;
    rotated << R * local.head<3>(), R * local.tail<3>();
    EXPECT_LT(relativeError(rotated, classical), kExact);
  }
  EXPECT_THROW(getFrameClassicalAcceleration(model, data, 0, ReferenceFrame::World),
               std::invalid_argument);
}

// Jcom against finite differences of the CoM; Jcom v = vcom; consistent CoM and mass.
inline void comJacobianMatchesFiniteDifferences(const Model& model, const Sample& s) {
  Data data(model), dq(model);
  const Eigen::Matrix3Xd Jcom = jacobianCenterOfMass(model, data, s.q);
  const Eigen::Vector3d com_from_jacobian = data.com;
  const Eigen::MatrixXd fd = manifoldCentralDifference(
      model, s.q,
      [&](const Eigen::VectorXd& q) { return Eigen::VectorXd(centerOfMass(model, dq, q)); },
      kFdStep);
  EXPECT_LT(relativeError(Jcom, fd), kFd) << "Jcom =\n" << Jcom << "\nfd =\n" << fd;
  centerOfMass(model, dq, s.q, s.v);
  EXPECT_LT(relativeError(com_from_jacobian, dq.com), 1e-12);
  EXPECT_LT(relativeError(centerOfMass(model, dq, s.q), com_from_jacobian), 1e-12);
  centerOfMass(model, dq, s.q, s.v);
  EXPECT_LT(relativeError(Eigen::Vector3d(Jcom * s.v), dq.vcom), kExact);
  EXPECT_NEAR(dq.mass, model.totalMass(), 1e-12 * model.totalMass());
}

// A_g v = h_g; the linear part is m vcom; the angular part equals the sum over bodies of
// (c_i - com) x m_i v_ci + R_i I_ci w_i, computed here from scratch.
inline void centroidalMapMatchesMomentum(const Model& model, const Sample& s) {
  Data data(model), dh(model);
  const Matrix6Xd Ag = computeCentroidalMap(model, data, s.q);
  const Vector6d hg = computeCentroidalMomentum(model, dh, s.q, s.v);
  EXPECT_LT(relativeError(Vector6d(Ag * s.v), hg), kExact);
  EXPECT_LT(relativeError(data.com, dh.com), 1e-12);
  EXPECT_LT(relativeError(Eigen::Vector3d(hg.head<3>()), Eigen::Vector3d(dh.mass * dh.vcom)),
            1e-12);
  Data dc(model);
  centerOfMass(model, dc, s.q, s.v);
  EXPECT_LT(relativeError(Eigen::Vector3d(hg.head<3>()), Eigen::Vector3d(dc.mass * dc.vcom)),
            kExact);
  // From scratch, body by body.
  forwardKinematics(model, dc, s.q, s.v);
  Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
  for (int i = 1; i < model.njoints(); ++i) {
    const Inertia& Y = model.inertias[i];
    if (Y.m <= 0) continue;
    const SE3& M = dc.oMi[i];
    const Eigen::Vector3d c_local = Y.com();
    const Eigen::Vector3d w_local = dc.v[i].tail<3>();
    const Eigen::Vector3d vc_local = dc.v[i].head<3>() + w_local.cross(c_local);
    const Eigen::Vector3d c = M.p + M.R * c_local, vc = M.R * vc_local;
    linear += Y.m * vc;
    angular += (c - dc.com).cross(Y.m * vc) + M.R * (Y.inertiaAboutCom() * w_local);
  }
  EXPECT_LT(relativeError(Eigen::Vector3d(hg.head<3>()), linear), kExact);
  EXPECT_LT(relativeError(Eigen::Vector3d(hg.tail<3>()), angular), kExact);
}

}  // namespace checks

}  // namespace stride
