#pragma once
// Recursive Newton-Euler inverse dynamics (Featherstone, RBDA §5.3):
//   tau = M(q) a + b(q, v),  b = C(q, v) v + g(q).
// Written in the joint frames: forward sweep for velocities, accelerations (gravity enters as a
// fictitious upward acceleration of the universe) and body forces; backward sweep projects and
// accumulates the forces.

#include "solver/multibody/data.hpp"

namespace stride {

// tau(q, v, a), written to data.tau and returned. Also fills data.liMi, oMi, v, a_gf, f.
const Eigen::VectorXd& rnea(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& v,
                            const Eigen::Ref<const Eigen::VectorXd>& a);
// b(q, v) = rnea(q, v, 0), written to data.nle.
const Eigen::VectorXd& nonLinearEffects(const Model& model, Data& data,
                                        const Eigen::Ref<const Eigen::VectorXd>& q,
                                        const Eigen::Ref<const Eigen::VectorXd>& v);
// The same, reading the placements of q from data.liMi instead of computing them: PRECONDITION
// data.liMi and data.oMi hold the placements of the configuration q to evaluate at, as crba(q),
// rnea(q, ...) or forwardKinematics(q) leave them (nothing checks it; a stale Data gives a silently
// wrong b). Saves the trigonometry and the SE3 products when the caller has just run crba for the
// same q, as contact dynamics does.
const Eigen::VectorXd& nonLinearEffectsFromKinematics(const Model& model, Data& data,
                                                      const Eigen::Ref<const Eigen::VectorXd>& v);
// g(q) = rnea(q, 0, 0), written to data.g (no velocity terms computed).
const Eigen::VectorXd& computeGeneralizedGravity(const Model& model, Data& data,
                                                 const Eigen::Ref<const Eigen::VectorXd>& q);

}  // namespace stride
