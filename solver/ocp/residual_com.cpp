#include "solver/ocp/residual_com.hpp"

#include <stdexcept>
#include <string>

namespace stride {

ComResidualData::ComResidualData(int dim, int ndx, int nu, int njoints)
    : ResidualData(dim, ndx, nu),
      Ycrb(njoints, Inertia::Zero()),
      ov(njoints, Vector6d::Zero()),
      H(njoints, Vector6d::Zero()) {}

namespace {
// Composite inertias (and, with momentum, composite momenta) of every subtree, in the world frame,
// from the knot's placements and velocities; then the CoM. The universe's fixed bodies are not
// part of the moving mass.
void compositeSweep(const Model& model, const Data& data, ComResidualData& d, bool momentum) {
  d.Ycrb[0] = Inertia::Zero();
  d.H[0].setZero();
  d.ov[0].setZero();
  for (int i = 1; i < model.njoints(); ++i) {
    d.Ycrb[i] = model.inertias[i].transformedBy(data.oMi[i]);
    if (momentum) {
      d.ov[i] = data.oMi[i].act(data.v[i]);
      d.H[i] = d.Ycrb[i] * d.ov[i];
    }
  }
  for (int i = model.njoints() - 1; i > 0; --i) {
    const int p = model.joints[i].parent;
    d.Ycrb[p] += d.Ycrb[i];
    if (momentum) d.H[p] += d.H[i];
  }
  d.mass = d.Ycrb[0].m;
  d.com = d.Ycrb[0].com();
  d.h = d.H[0];
}

int checkedJoints(const Model& model, const char* who) {
  if (!(model.totalMass() > 0.0))
    throw std::invalid_argument(std::string(who) + ": model '" + model.name +
                                "' has no moving mass");
  return model.njoints();
}
}  // namespace

// ---------------------------------------------------------------- CoM

ComPositionResidual::ComPositionResidual(const Model& model, int nu,
                                         const Eigen::Vector3d& reference)
    : Residual(3, model.nv, nu, Dependence::Configuration),
      njoints_(checkedJoints(model, "ComPositionResidual")),
      reference_(reference) {}

std::unique_ptr<ResidualData> ComPositionResidual::createData() const {
  return std::make_unique<ComResidualData>(3, 2 * nv(), nu(), njoints_);
}

void ComPositionResidual::calc(ResidualData& d, const KnotContext& ctx,
                               const Eigen::Ref<const Eigen::VectorXd>&,
                               const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& cd = static_cast<ComResidualData&>(d);
  compositeSweep(ctx.model, ctx.data, cd, false);
  cd.r.head<3>() = cd.com - reference_;
}

void ComPositionResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                   const Eigen::Ref<const Eigen::VectorXd>&,
                                   const Eigen::Ref<const Eigen::VectorXd>&) const {
  // Dof k moves its joint's subtree with the world twist S_k = [ν; ω]: the subtree's first moment
  // moves by m ν + ω x (m c), the linear part of Ycrb S_k.
  auto& cd = static_cast<ComResidualData&>(d);
  const Model& model = ctx.model;
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    for (int k = j.idx_v; k < j.idx_v + j.nv; ++k)
      cd.Rx.block<3, 1>(0, k) = (cd.Ycrb[i] * Vector6d(ctx.data.J.col(k))).head<3>() / cd.mass;
  }
}

// ---------------------------------------------------------------- centroidal momentum

CentroidalMomentumResidual::CentroidalMomentumResidual(const Model& model, int nu,
                                                       const Vector6d& reference)
    : Residual(6, model.nv, nu, Dependence::State),
      njoints_(checkedJoints(model, "CentroidalMomentumResidual")),
      reference_(reference) {}

std::unique_ptr<ResidualData> CentroidalMomentumResidual::createData() const {
  return std::make_unique<ComResidualData>(6, 2 * nv(), nu(), njoints_);
}

void CentroidalMomentumResidual::calc(ResidualData& d, const KnotContext& ctx,
                                      const Eigen::Ref<const Eigen::VectorXd>&,
                                      const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& cd = static_cast<ComResidualData&>(d);
  compositeSweep(ctx.model, ctx.data, cd, true);
  cd.r.head<3>() = cd.h.head<3>() - reference_.head<3>();
  cd.r.tail<3>() = cd.h.tail<3>() - cd.com.cross(cd.h.head<3>()) - reference_.tail<3>();
}

void CentroidalMomentumResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                          const Eigen::Ref<const Eigen::VectorXd>&,
                                          const Eigen::Ref<const Eigen::VectorXd>&) const {
  // Moving dof k of joint i (world twist S_k, parent joint λ) carries the subtree of i rigidly:
  // each body's world inertia turns, Y' = S_k x* Y - Y S_k x, and its velocity gains
  // S_k x (ov - ov_λ) (the axes below k turn). Per body, d(Y ov) = S_k x* (Y ov) + Y (ov_λ x S_k);
  // summed over the subtree, with the composite momentum H_i and composite inertia Ycrb_i,
  //   ∂h_o/∂q_k = S_k x* H_i + Ycrb_i (ov_λ x S_k)       (momentum about the world origin).
  // h_g moves the moment to the CoM: ang = h_o,ang - c x h_lin, whose derivative also has
  // -∂c x h_lin with ∂c = Jcom_k = (Ycrb_i S_k)_lin / m. ∂h_g/∂v_k is that column of A_g.
  auto& cd = static_cast<ComResidualData&>(d);
  const Model& model = ctx.model;
  const int nv = this->nv();
  const Eigen::Vector3d& c = cd.com;
  const Eigen::Vector3d hlin = cd.h.head<3>();
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    const Vector6d& ov_parent = cd.ov[j.parent];
    for (int k = j.idx_v; k < j.idx_v + j.nv; ++k) {
      const Vector6d S = ctx.data.J.col(k);
      const Vector6d a = cd.Ycrb[i] * S;
      const Vector6d dh = forceCross(S, cd.H[i]) + cd.Ycrb[i] * motionCross(ov_parent, S);
      const Eigen::Vector3d dc = a.head<3>() / cd.mass;
      cd.Rx.col(k).head<3>() = dh.head<3>();
      cd.Rx.col(k).tail<3>() = dh.tail<3>() - c.cross(dh.head<3>()) - dc.cross(hlin);
      cd.Rx.col(nv + k).head<3>() = a.head<3>();
      cd.Rx.col(nv + k).tail<3>() = a.tail<3>() - c.cross(a.head<3>());
    }
  }
}

}  // namespace stride
