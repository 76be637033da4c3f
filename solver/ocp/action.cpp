#include "solver/ocp/action.hpp"

#include "solver/multibody/lie_group.hpp"

namespace stride {

StateSpace::StateSpace(const Model& model)
    : model_(&model), nx_(model.nq + model.nv), ndx_(2 * model.nv) {}

StateSpace::StateSpace(int n) : nx_(n), ndx_(n) {}

void StateSpace::integrate(const Eigen::Ref<const Eigen::VectorXd>& x,
                           const Eigen::Ref<const Eigen::VectorXd>& dx,
                           Eigen::Ref<Eigen::VectorXd> out) const {
  if (!model_) {
    out = x + dx;
    return;
  }
  const int nq = model_->nq, nv = model_->nv;
  stride::integrate(*model_, x.head(nq), dx.head(nv), out.head(nq));
  out.tail(nv) = x.tail(nv) + dx.tail(nv);
}

void StateSpace::difference(const Eigen::Ref<const Eigen::VectorXd>& x0,
                            const Eigen::Ref<const Eigen::VectorXd>& x1,
                            Eigen::Ref<Eigen::VectorXd> out) const {
  if (!model_) {
    out = x1 - x0;
    return;
  }
  const int nq = model_->nq, nv = model_->nv;
  stride::difference(*model_, x0.head(nq), x1.head(nq), out.head(nv));
  out.tail(nv) = x1.tail(nv) - x0.tail(nv);
}

Eigen::VectorXd StateSpace::zero() const {
  if (!model_) return Eigen::VectorXd::Zero(nx_);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(nx_);
  x.head(model_->nq) = neutral(*model_);
  return x;
}

const char* toString(KnotStatus status) {
  switch (status) {
    case KnotStatus::Ok:
      return "ok";
    case KnotStatus::NonFinite:
      return "non-finite value";
    case KnotStatus::DynamicsFailure:
      return "contact dynamics failed (singular KKT system)";
  }
  return "?";
}

ActionData::ActionData(int nx, int ndx, int nu)
    : x_next(Eigen::VectorXd::Zero(nx)),
      Fx(Eigen::MatrixXd::Zero(ndx, ndx)),
      Fu(Eigen::MatrixXd::Zero(ndx, nu)),
      Lx(Eigen::VectorXd::Zero(ndx)),
      Lu(Eigen::VectorXd::Zero(nu)),
      Lxx(Eigen::MatrixXd::Zero(ndx, ndx)),
      Lxu(Eigen::MatrixXd::Zero(ndx, nu)),
      Luu(Eigen::MatrixXd::Zero(nu, nu)) {}

}  // namespace stride
