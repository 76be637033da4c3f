#include "solver/ocp/residual_state.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "solver/multibody/lie_group.hpp"

namespace stride {

namespace {
SE3 freeFlyerPlacement(const Eigen::Ref<const Eigen::VectorXd>& q) {
  return SE3(Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix(), q.head<3>());
}
}  // namespace

// ---------------------------------------------------------------- StateResidual

StateResidual::StateResidual(const Model& model, int nu)
    : Residual(2 * model.nv, model.nv, nu, Dependence::State),
      nq_(model.nq),
      free_flyer_(model.hasFreeFlyer()),
      x_ref_(model.nq + model.nv) {
  x_ref_.head(model.nq) = neutral(model);
  x_ref_.tail(model.nv).setZero();
}

StateResidual::StateResidual(const Model& model, int nu, const Eigen::VectorXd& x_ref)
    : StateResidual(model, nu) {
  setReference(x_ref);
}

void StateResidual::setReference(const Eigen::Ref<const Eigen::VectorXd>& x_ref) {
  if (x_ref.size() != x_ref_.size())
    throw std::invalid_argument("StateResidual::setReference: reference of size " +
                                std::to_string(x_ref.size()) +
                                ", expected nq + nv = " + std::to_string(x_ref_.size()));
  x_ref_ = x_ref;
}

std::unique_ptr<ResidualData> StateResidual::createData() const {
  auto d = Residual::createData();
  // Outside a free-flyer's 6 x 6 block Rx is constant: set once here, never rewritten.
  d->Rx.setIdentity();
  return d;
}

void StateResidual::calc(ResidualData& d, const KnotContext& ctx,
                         const Eigen::Ref<const Eigen::VectorXd>& x,
                         const Eigen::Ref<const Eigen::VectorXd>&) const {
  const int nv = this->nv();
  difference(ctx.model, x_ref_.head(nq_), x.head(nq_), d.r.head(nv));
  d.r.tail(nv) = x.tail(nv) - x_ref_.tail(nv);
}

void StateResidual::calcDiff(ResidualData& d, const KnotContext&,
                             const Eigen::Ref<const Eigen::VectorXd>& x,
                             const Eigen::Ref<const Eigen::VectorXd>&) const {
  if (!free_flyer_) return;
  // The base block of ∂(q ⊖ q_ref)/∂q: log6(M_ref^-1 M) moved by M exp(δ) is Jlog6 δ.
  const SE3 delta = freeFlyerPlacement(x_ref_).actInv(freeFlyerPlacement(x));
  d.Rx.topLeftCorner<6, 6>() = Jlog6(delta);
}

void StateResidual::addGaussNewton(const ResidualData& d,
                                   const Eigen::Ref<const Eigen::VectorXd>& g,
                                   const Eigen::Ref<const Eigen::VectorXd>& h,
                                   CostDerivatives& out) const {
  const int ndx = 2 * nv();
  const int k = free_flyer_ ? 6 : 0;
  if (free_flyer_) {
    const Matrix6d B = d.Rx.topLeftCorner<6, 6>();
    out.Lx.head<6>().noalias() += B.transpose() * g.head<6>();
    out.Lxx.topLeftCorner<6, 6>().noalias() += B.transpose() * h.head<6>().asDiagonal() * B;
  }
  out.Lx.segment(k, ndx - k) += g.segment(k, ndx - k);
  out.Lxx.diagonal().segment(k, ndx - k) += h.segment(k, ndx - k);
}

// ---------------------------------------------------------------- ControlResidual

ControlResidual::ControlResidual(const Model& model, int nu)
    : Residual(nu, model.nv, nu, Dependence::Control), u_ref_(Eigen::VectorXd::Zero(nu)) {}

ControlResidual::ControlResidual(const Model& model, int nu, const Eigen::VectorXd& u_ref)
    : ControlResidual(model, nu) {
  setReference(u_ref);
}

void ControlResidual::setReference(const Eigen::Ref<const Eigen::VectorXd>& u_ref) {
  if (u_ref.size() != u_ref_.size())
    throw std::invalid_argument("ControlResidual::setReference: reference of size " +
                                std::to_string(u_ref.size()) +
                                ", expected nu = " + std::to_string(u_ref_.size()));
  u_ref_ = u_ref;
}

std::unique_ptr<ResidualData> ControlResidual::createData() const {
  auto d = Residual::createData();
  d->Ru.setIdentity();
  return d;
}

void ControlResidual::calc(ResidualData& d, const KnotContext&,
                           const Eigen::Ref<const Eigen::VectorXd>&,
                           const Eigen::Ref<const Eigen::VectorXd>& u) const {
  d.r = u - u_ref_;
}

void ControlResidual::calcDiff(ResidualData&, const KnotContext&,
                               const Eigen::Ref<const Eigen::VectorXd>&,
                               const Eigen::Ref<const Eigen::VectorXd>&) const {}

void ControlResidual::addGaussNewton(const ResidualData&,
                                     const Eigen::Ref<const Eigen::VectorXd>& g,
                                     const Eigen::Ref<const Eigen::VectorXd>& h,
                                     CostDerivatives& out) const {
  out.Lu += g;
  out.Luu.diagonal() += h;
}

// ---------------------------------------------------------------- JointLimitResidual

namespace {
int actuatedJoints(const Model& model) {
  return model.hasFreeFlyer() ? model.nv - 6 : model.nv;
}
}  // namespace

JointLimitResidual::JointLimitResidual(const Model& model, int nu)
    : Residual(2 * actuatedJoints(model), model.nv, nu, Dependence::State),
      nj_(actuatedJoints(model)),
      q_offset_(model.hasFreeFlyer() ? 7 : 0),
      v_offset_(model.hasFreeFlyer() ? 6 : 0) {
  // Every joint after the free-flyer is 1-dof and Euclidean: q and v entries pair up one to one.
  if (model.nq - q_offset_ != nj_)
    throw std::invalid_argument("JointLimitResidual: model '" + model.name +
                                "' has joints other than 1-dof ones below its root");
}

Activation JointLimitResidual::activation(const Model& model, double weight, double margin) {
  if (!(margin > 0.0 && margin <= 1.0))
    throw std::invalid_argument("JointLimitResidual::activation: margin must be in (0, 1]");
  const int nj = actuatedJoints(model);
  const int qo = model.hasFreeFlyer() ? 7 : 0, vo = model.hasFreeFlyer() ? 6 : 0;
  Eigen::VectorXd lower(2 * nj), upper(2 * nj);
  for (int i = 0; i < nj; ++i) {
    const double lo = model.lowerPositionLimit[qo + i], hi = model.upperPositionLimit[qo + i];
    if (std::isfinite(lo) && std::isfinite(hi)) {
      const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo) * margin;
      lower[i] = mid - half;
      upper[i] = mid + half;
    } else {
      lower[i] = lo;
      upper[i] = hi;
    }
    const double vmax = model.velocityLimit[vo + i] * margin;
    lower[nj + i] = -vmax;
    upper[nj + i] = vmax;
  }
  return Activation::bounds(lower, upper, weight);
}

std::unique_ptr<ResidualData> JointLimitResidual::createData() const {
  auto d = Residual::createData();
  const int nv = this->nv();
  for (int i = 0; i < nj_; ++i) {
    d->Rx(i, v_offset_ + i) = 1.0;
    d->Rx(nj_ + i, nv + v_offset_ + i) = 1.0;
  }
  return d;
}

void JointLimitResidual::calc(ResidualData& d, const KnotContext& ctx,
                              const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>&) const {
  d.r.head(nj_) = x.segment(q_offset_, nj_);
  d.r.tail(nj_) = x.segment(ctx.model.nq + v_offset_, nj_);
}

void JointLimitResidual::calcDiff(ResidualData&, const KnotContext&,
                                  const Eigen::Ref<const Eigen::VectorXd>&,
                                  const Eigen::Ref<const Eigen::VectorXd>&) const {}

void JointLimitResidual::addGaussNewton(const ResidualData&,
                                        const Eigen::Ref<const Eigen::VectorXd>& g,
                                        const Eigen::Ref<const Eigen::VectorXd>& h,
                                        CostDerivatives& out) const {
  const int nv = this->nv();
  out.Lx.segment(v_offset_, nj_) += g.head(nj_);
  out.Lx.segment(nv + v_offset_, nj_) += g.tail(nj_);
  out.Lxx.diagonal().segment(v_offset_, nj_) += h.head(nj_);
  out.Lxx.diagonal().segment(nv + v_offset_, nj_) += h.tail(nj_);
}

}  // namespace stride
