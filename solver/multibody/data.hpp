#pragma once
// Every workspace the multibody algorithms write, allocated once from a Model. After construction
// no algorithm allocates (tests/multibody/test_no_alloc.cpp proves it). Names follow Featherstone:
// liMi parent->child placement, oMi world placement, v/a body velocity/acceleration in the joint
// frame, f body force, "o" prefix = expressed in the world frame.

#include <vector>

#include "solver/multibody/model.hpp"

namespace stride {

struct Data {
  explicit Data(const Model& model);

  // Kinematics (forwardKinematics, kinematics.hpp).
  std::vector<SE3> liMi;    // joint placement relative to its parent joint
  std::vector<SE3> oMi;     // joint placement in the world
  std::vector<Vector6d> v;  // joint spatial velocity, in the joint frame
  std::vector<Vector6d> a;  // joint spatial acceleration (no gravity), in the joint frame
  std::vector<SE3> oMf;     // frame placements (updateFramePlacements, frames.hpp)

  // RNEA (rnea.hpp): a_gf = acceleration including -gravity; f = net body force.
  std::vector<Vector6d> a_gf;
  std::vector<Vector6d> f;
  Eigen::VectorXd tau;  // rnea output
  Eigen::VectorXd nle;  // nonLinearEffects output: b(q, v) = C(q, v) v + g(q)
  Eigen::VectorXd g;    // computeGeneralizedGravity output

  // World-frame quantities shared by CRBA, ABA, Jacobians, CoM and centroidal algorithms.
  Matrix6Xd J;                  // joint Jacobian columns in the world frame (motion subspaces)
  std::vector<Inertia> oYcrb;   // composite (subtree) inertia, world frame
  std::vector<Inertia> oYbody;  // each body's own inertia, world frame (crba)
  std::vector<Vector6d> ov;     // spatial velocity in the world frame
  Eigen::MatrixXd M;            // joint-space inertia matrix (crba), full symmetric

  // ABA (aba.hpp), world-frame articulated-body sweeps.
  std::vector<Matrix6d> oYaba;   // articulated inertia
  std::vector<Vector6d> of;      // articulated bias force
  std::vector<Vector6d> oc;      // velocity-product acceleration ov x (S qd)
  std::vector<Vector6d> oa;      // spatial acceleration in the world frame (aba)
  Matrix6Xd U;                   // Ia S per dof
  Eigen::VectorXd Dinv;          // (S^T Ia S)^-1 for 1-dof joints
  Eigen::VectorXd u;             // tau - S^T pA
  Eigen::LLT<Matrix6d> rootLLT;  // S^T Ia S for a free-flyer root (6x6)
  Eigen::VectorXd ddq;           // aba output

  // RNEA derivatives (rnea_derivatives.hpp), world frame. Composite (subtree) quantities:
  // Time derivative of the composite inertia, Σ v x* Y - Y v x, stored in inertia form (m = 0,
  // h = ḣ, I = İ): it is symmetric with an inertia's structure (rnea_derivatives.cpp).
  std::vector<Inertia> oBcrb;
  std::vector<Vector6d> oh;  // composite momentum
  std::vector<Vector6d> oF;  // composite force
  // Per-dof 6-vectors (columns), see rnea_derivatives.cpp for their meaning.
  Matrix6Xd dW, dC, dE, dA, dB, dG, dH;
  Eigen::MatrixXd dtau_dq, dtau_dv;  // nv x nv

  // Tree-sparse L^T D L factorization of M (cholesky.hpp): D on the diagonal of Ltdl, L (unit
  // lower triangular, nonzero only where the column's dof supports the row's) below it.
  Eigen::MatrixXd Ltdl;
  Eigen::MatrixXd Minv;            // M^-1 = ∂v̇/∂τ (computeABADerivatives)
  Eigen::MatrixXd ddq_dq, ddq_dv;  // ABA derivatives; d ddq / d tau = Minv
  RowMatrixXd rhs3;                // nv x 3nv: stacked right-hand sides of one M^-1 solve

  // Centre of mass (center_of_mass.hpp) and centroidal momentum (centroidal.hpp).
  double mass = 0.0;  // total moving mass
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Vector3d vcom = Eigen::Vector3d::Zero();
  Eigen::Matrix3Xd Jcom;           // 3 x nv
  Vector6d hg = Vector6d::Zero();  // centroidal momentum [linear; angular about the CoM]
  Matrix6Xd Ag;                    // centroidal momentum matrix, 6 x nv, hg = Ag v
};

}  // namespace stride
