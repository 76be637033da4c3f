#pragma once
// The configuration manifold: SO(3)/SE(3) exponential and logarithm with their Jacobians, and the
// whole-robot integrate (q ⊕ v) and difference (q1 ⊖ q0) with theirs. Conventions
// (ARCHITECTURE.md §3): a free-flyer moves by the SE(3) exponential of its base-frame velocity,
// q ⊕ v = M(q) exp(v); q1 ⊖ q0 = log(M(q0)^-1 M(q1)). 1-dof joints are Euclidean.
// Formulas: Barfoot, "State Estimation for Robotics", §7.1 (right Jacobians).

#include <random>

#include "solver/multibody/model.hpp"

namespace stride {

// ---- SO(3) ----
Eigen::Matrix3d exp3(const Eigen::Vector3d& w);
Eigen::Vector3d log3(const Eigen::Matrix3d& R);
// Right Jacobian: exp3(w + d) ≈ exp3(w) exp3(Jexp3(w) d).
Eigen::Matrix3d Jexp3(const Eigen::Vector3d& w);
// Its inverse, the Jacobian of log3 at R = exp3(w): log3(R exp3(d)) ≈ w + Jlog3(R) d.
Eigen::Matrix3d Jlog3(const Eigen::Matrix3d& R);

// ---- SE(3), tangent vectors [linear; angular] ----
SE3 exp6(const Vector6d& xi);
Vector6d log6(const SE3& M);
Matrix6d Jexp6(const Vector6d& xi);  // right Jacobian
Matrix6d Jlog6(const SE3& M);        // its inverse at xi = log6(M)

// ---- whole configuration ----
enum class ArgumentPosition { First, Second };

Eigen::VectorXd neutral(const Model& model);
// Uniform within the position limits; where a limit is infinite, within [-1, 1] (free-flyer
// translation) or [-pi, pi] (revolute); uniformly random unit quaternion.
Eigen::VectorXd randomConfiguration(const Model& model, std::mt19937& rng);
// Normalizes the free-flyer quaternion in place.
void normalize(const Model& model, Eigen::Ref<Eigen::VectorXd> q);
bool isNormalized(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                  double tolerance = 1e-10);

void integrate(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
               const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> qout);
Eigen::VectorXd integrate(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                          const Eigen::Ref<const Eigen::VectorXd>& v);
// q1 ⊖ q0: the v such that q0 ⊕ v = q1.
void difference(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q0,
                const Eigen::Ref<const Eigen::VectorXd>& q1, Eigen::Ref<Eigen::VectorXd> dv);
Eigen::VectorXd difference(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q0,
                           const Eigen::Ref<const Eigen::VectorXd>& q1);

// Jacobians (nv x nv) of q ⊕ v with respect to q (First) or v (Second).
void dIntegrate(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::MatrixXd> J,
                ArgumentPosition arg);
// Jacobians (nv x nv) of q1 ⊖ q0 with respect to q0 (First) or q1 (Second).
void dDifference(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q0,
                 const Eigen::Ref<const Eigen::VectorXd>& q1, Eigen::Ref<Eigen::MatrixXd> J,
                 ArgumentPosition arg);

}  // namespace stride
