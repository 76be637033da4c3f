#include "solver/ocp/cost.hpp"

#include <algorithm>
#include <stdexcept>

namespace stride {

int CostModel::add(const std::string& name, std::unique_ptr<Residual> residual,
                   Activation activation, double weight) {
  if (!residual) throw std::invalid_argument("CostModel::add: null residual for '" + name + "'");
  if (find(name) >= 0) throw std::invalid_argument("CostModel::add: duplicate term '" + name + "'");
  if (residual->nv() != nv_ || residual->nu() != nu_)
    throw std::invalid_argument("CostModel::add: term '" + name +
                                "' is built for another state or control dimension");
  if (activation.dim() != residual->dim())
    throw std::invalid_argument("CostModel::add: term '" + name + "' has an activation of size " +
                                std::to_string(activation.dim()) + " for a residual of size " +
                                std::to_string(residual->dim()));
  terms_.push_back(CostTerm{name, std::move(residual), std::move(activation), weight, true});
  return size() - 1;
}

int CostModel::find(const std::string& name) const {
  for (int i = 0; i < size(); ++i)
    if (terms_[i].name == name) return i;
  return -1;
}

int CostModel::maxDim() const {
  int m = 0;
  for (const CostTerm& t : terms_) m = std::max(m, t.residual->dim());
  return m;
}

CostData CostModel::createData() const {
  const int m = maxDim();
  CostData d{{},
             Eigen::VectorXd::Zero(m),
             Eigen::VectorXd::Zero(m),
             Eigen::MatrixXd::Zero(m, 2 * nv_),
             Eigen::MatrixXd::Zero(m, nu_),
             0.0};
  d.residuals.reserve(terms_.size());
  for (const CostTerm& t : terms_) d.residuals.push_back(t.residual->createData());
  return d;
}

double CostModel::calc(CostData& d, const KnotContext& ctx,
                       const Eigen::Ref<const Eigen::VectorXd>& x,
                       const Eigen::Ref<const Eigen::VectorXd>& u) const {
  d.value = 0.0;
  for (int i = 0; i < size(); ++i) {
    const CostTerm& t = terms_[i];
    if (!t.active || t.weight == 0.0) continue;
    ResidualData& rd = *d.residuals[i];
    t.residual->calc(rd, ctx, x, u);
    d.value += t.weight * t.activation.value(rd.r);
  }
  return d.value;
}

namespace {
// Zeroes a block in one fill when its columns are contiguous (a whole matrix behind a Ref): through
// the Ref, Eigen cannot know it and fills column by column, a library call per column (a knot's
// Lxx alone is 2nv of them).
void zero(Eigen::Ref<Eigen::MatrixXd> A) {
  if (A.outerStride() == A.rows())
    Eigen::Map<Eigen::VectorXd>(A.data(), A.size()).setZero();
  else
    A.setZero();
}
}  // namespace

double CostModel::calcDiff(CostData& d, const KnotContext& ctx,
                           const Eigen::Ref<const Eigen::VectorXd>& x,
                           const Eigen::Ref<const Eigen::VectorXd>& u,
                           Eigen::Ref<Eigen::VectorXd> Lx, Eigen::Ref<Eigen::VectorXd> Lu,
                           Eigen::Ref<Eigen::MatrixXd> Lxx, Eigen::Ref<Eigen::MatrixXd> Lxu,
                           Eigen::Ref<Eigen::MatrixXd> Luu) const {
  Lx.setZero();
  Lu.setZero();
  zero(Lxx);
  zero(Lxu);
  zero(Luu);
  CostDerivatives out{Lx, Lu, Lxx, Lxu, Luu, d.HRx, d.HRu};
  d.value = 0.0;
  for (int i = 0; i < size(); ++i) {
    const CostTerm& t = terms_[i];
    if (!t.active || t.weight == 0.0) continue;
    ResidualData& rd = *d.residuals[i];
    const int m = t.residual->dim();
    t.residual->calc(rd, ctx, x, u);
    auto g = d.g.head(m);
    auto h = d.h.head(m);
    d.value += t.weight * t.activation.derivatives(rd.r, g, h);
    // A term whose activation has zero gradient and curvature adds nothing to the derivatives:
    // a bounds activation inside its bounds (a friction cone with its force well inside, on most
    // stance knots). Its Jacobians are then not even computed (for a cone, two products with the
    // force derivatives), and no product runs.
    if (g.isZero(0.0) && h.isZero(0.0)) continue;
    t.residual->calcDiff(rd, ctx, x, u);
    g *= t.weight;
    h *= t.weight;
    t.residual->addGaussNewton(rd, g, h, out);
  }
  return d.value;
}

}  // namespace stride
