#include "solver/ocp/residual.hpp"

namespace stride {

ResidualData::ResidualData(int dim, int ndx, int nu)
    : r(Eigen::VectorXd::Zero(dim)),
      Rx(Eigen::MatrixXd::Zero(dim, ndx)),
      Ru(Eigen::MatrixXd::Zero(dim, nu)),
      J6(Matrix6Xd::Zero(6, ndx / 2)) {}

void Residual::addGaussNewton(const ResidualData& d, const Eigen::Ref<const Eigen::VectorXd>& g,
                              const Eigen::Ref<const Eigen::VectorXd>& h,
                              CostDerivatives& out) const {
  const int m = dim_;
  const bool has_x = dependence_ != Dependence::Control;
  const bool has_u = dependence_ == Dependence::Control || dependence_ == Dependence::StateControl;
  // Only the columns that can be nonzero: a configuration residual touches the dq block only.
  const int nx = dependence_ == Dependence::Configuration ? nv_ : 2 * nv_;
  if (has_x) {
    const auto Rx = d.Rx.leftCols(nx);
    auto HRx = out.HRx.topLeftCorner(m, nx);
    HRx.noalias() = h.asDiagonal() * Rx;
    out.Lx.head(nx).noalias() += Rx.transpose() * g;
    out.Lxx.topLeftCorner(nx, nx).noalias() += Rx.transpose() * HRx;
    if (has_u) out.Lxu.topRows(nx).noalias() += HRx.transpose() * d.Ru;
  }
  if (has_u) {
    auto HRu = out.HRu.topRows(m);
    HRu.noalias() = h.asDiagonal() * d.Ru;
    out.Lu.noalias() += d.Ru.transpose() * g;
    out.Luu.noalias() += d.Ru.transpose() * HRu;
  }
}

}  // namespace stride
