#include "solver/multibody/inverse_kinematics.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {

const char* toString(IkStatus status) {
  switch (status) {
    case IkStatus::Converged:
      return "converged";
    case IkStatus::MaxIterations:
      return "not within tolerance after the last iteration (target out of reach?)";
    case IkStatus::NotFinite:
      return "non-finite configuration or error";
  }
  return "?";
}

InverseKinematics::InverseKinematics(const Model& model, std::vector<IkTarget> targets,
                                     std::vector<int> columns,
                                     const InverseKinematicsOptions& options)
    : model_(model),
      targets_(std::move(targets)),
      columns_(std::move(columns)),
      options_(options),
      data_(model),
      J_frame_(Matrix6Xd::Zero(6, model.nv)) {
  const int nf = static_cast<int>(model.frames.size()), nv = model.nv;
  if (targets_.empty()) throw std::invalid_argument("InverseKinematics: no target");
  for (const IkTarget& t : targets_) {
    if (t.frame < 0 || t.frame >= nf)
      throw std::invalid_argument("InverseKinematics: no frame " + std::to_string(t.frame));
    if (t.dim != 3 && t.dim != 6)
      throw std::invalid_argument("InverseKinematics: frame '" + model.frames[t.frame].name +
                                  "': a target has 3 (position) or 6 (placement) rows, not " +
                                  std::to_string(t.dim));
    if (t.dim == 6 && t.error == ReferenceFrame::World)
      throw std::invalid_argument("InverseKinematics: frame '" + model.frames[t.frame].name +
                                  "': a placement error is Local or LocalWorldAligned");
    rows_ += t.dim;
  }
  if (columns_.empty()) throw std::invalid_argument("InverseKinematics: no column moves");
  std::vector<char> seen(nv, 0);
  for (int c : columns_) {
    if (c < 0 || c >= nv || seen[c])
      throw std::invalid_argument("InverseKinematics: column " + std::to_string(c) +
                                  " out of range [0, nv) or listed twice");
    seen[c] = 1;
  }
  const int n = static_cast<int>(columns_.size());
  J6_.setZero(6, n);
  J_.setZero(rows_, n);
  JJt_.setZero(rows_, rows_);
  e_.setZero(rows_);
  y_.setZero(rows_);
  dq_.setZero(n);
  dv_.setZero(nv);
  q_next_.setZero(model.nq);
  // The factorization's storage at its size, by a first factorization (of the identity): moving
  // a sized but never computed LDLT in (LDLT(rows_)) read its unset ComputationInfo, which GCC's
  // UBSan reports as an invalid enum load.
  ldlt_.compute(Eigen::MatrixXd::Identity(rows_, rows_));
}

std::vector<int> InverseKinematics::jointColumns(const Model& model) {
  const int first = model.hasFreeFlyer() ? 6 : 0;
  std::vector<int> columns;
  for (int k = first; k < model.nv; ++k) columns.push_back(k);
  return columns;
}

void InverseKinematics::evaluate(Data& data) {
  const int n = static_cast<int>(columns_.size());
  int r = 0;
  for (const IkTarget& t : targets_) {
    const SE3& M = updateFramePlacement(model_, data, t.frame);
    if (t.dim == 6 && t.error == ReferenceFrame::Local) {
      // d/dq log6(M*⁻¹ M_f) = Jlog6 J_local (the right Jacobian of the log: a local motion of the
      // frame composes on the right).
      const SE3 error = t.placement.actInv(M);
      getFrameJacobian(model_, data, t.frame, ReferenceFrame::Local, J_frame_);
      for (int k = 0; k < n; ++k) J6_.col(k) = J_frame_.col(columns_[k]);
      e_.segment<6>(r) = log6(error);
      J_.middleRows<6>(r).noalias() = Jlog6(error) * J6_;  // no temporary: allocates nothing
    } else {
      getFrameJacobian(model_, data, t.frame, ReferenceFrame::LocalWorldAligned, J_frame_);
      e_.segment<3>(r) = M.p - t.placement.p;
      for (int k = 0; k < n; ++k) J_.col(k).segment<3>(r) = J_frame_.col(columns_[k]).head<3>();
      if (t.dim == 6) {
        e_.segment<3>(r + 3) = log3(M.R * t.placement.R.transpose());
        for (int k = 0; k < n; ++k)
          J_.col(k).segment<3>(r + 3) = J_frame_.col(columns_[k]).tail<3>();
      }
    }
    r += t.dim;
  }
}

void InverseKinematics::dampedStep(Eigen::Ref<Eigen::VectorXd> dv) {
  JJt_.noalias() = J_ * J_.transpose();
  JJt_.diagonal().array() += options_.damping;
  ldlt_.compute(JJt_);
  y_ = ldlt_.solve(e_);
  // dq = -Jᵀ (J Jᵀ + μ I)⁻¹ e, then into the velocity's columns.
  dq_.noalias() = -J_.transpose() * y_;
  dv.setZero();
  for (std::size_t k = 0; k < columns_.size(); ++k) dv[columns_[k]] = dq_[k];
}

double InverseKinematics::stepFromKinematics(Data& data, Eigen::Ref<Eigen::VectorXd> dv) {
  evaluate(data);
  const double norm = e_.norm();
  if (norm > options_.max_error) e_ *= options_.max_error / norm;
  dampedStep(dv);
  return norm;
}

IkResult InverseKinematics::solve(Eigen::Ref<Eigen::VectorXd> q) {
  if (q.size() != model_.nq)
    throw std::invalid_argument("InverseKinematics::solve: q has size " + std::to_string(q.size()) +
                                ", expected nq = " + std::to_string(model_.nq));
  IkResult result;
  for (int it = 0;; ++it) {
    result.iterations = it;
    if (!q.allFinite()) {
      result.status = IkStatus::NotFinite;
      return result;
    }
    computeJointJacobians(model_, data_, q);
    evaluate(data_);
    result.error = e_.norm();
    if (!std::isfinite(result.error)) {
      result.status = IkStatus::NotFinite;
      return result;
    }
    if (result.error < options_.tolerance) {
      result.status = IkStatus::Converged;
      return result;
    }
    if (it == options_.max_iterations) {
      result.status = IkStatus::MaxIterations;
      return result;
    }
    const double norm = result.error;
    if (norm > options_.max_error) e_ *= options_.max_error / norm;
    dampedStep(dv_);
    integrate(model_, q, dv_, q_next_);
    q = q_next_;
  }
}

}  // namespace stride
