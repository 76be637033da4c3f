#include "solver/ocp/residual.hpp"

namespace stride {

ResidualData::ResidualData(int dim, int ndx, int nu)
    : r(Eigen::VectorXd::Zero(dim)),
      Rx(Eigen::MatrixXd::Zero(dim, ndx)),
      Ru(Eigen::MatrixXd::Zero(dim, nu)),
      J6(Matrix6Xd::Zero(6, ndx / 2)) {}

namespace {
// Up to this many rows with curvature, the Hessian products run as rank-1 updates over those rows
// only; above it, as dense products over all rows. A bounds activation (friction cone, joint
// limits) has h = 0 on every row inside its bounds, so a violated cone has typically one row
// with curvature out of five. Measured (36 x 36 Lxx, 36 x 12 Lxu, one row of five curved): the
// rank-1 updates take ~0.25 us, the two GEMMs ~1.1 us; with three of three rows curved
// (a foot's translation, 18 columns) the GEMM is faster (0.40 against 0.45 us).
constexpr int kRankOneRows = 2;
constexpr int kMaxRankOneColumns = 256;
}  // namespace

void Residual::addGaussNewton(const ResidualData& d, const Eigen::Ref<const Eigen::VectorXd>& g,
                              const Eigen::Ref<const Eigen::VectorXd>& h,
                              CostDerivatives& out) const {
  const int m = dim_;
  const bool has_x = dependence_ != Dependence::Control;
  const bool has_u = dependence_ == Dependence::Control || dependence_ == Dependence::StateControl;
  // Only the columns that can be nonzero: a configuration residual touches the dq block only.
  const int nx = dependence_ == Dependence::Configuration ? nv_ : 2 * nv_;
  int curved[kRankOneRows];
  int nh = 0;
  for (int i = 0; i < m && nh <= kRankOneRows; ++i)
    if (h[i] != 0.0) {
      if (nh < kRankOneRows) curved[nh] = i;
      ++nh;
    }
  if (nh <= kRankOneRows && nx <= kMaxRankOneColumns && nu_ <= kMaxRankOneColumns) {
    // L.. += h_i r_iᵀ r_i over the curved rows i, r_i = [Rx_i, Ru_i]: each row gathered into a
    // contiguous buffer (Rx is column-major, its rows strided), then column updates.
    double row[2 * kMaxRankOneColumns];
    for (int a = 0; a < nh; ++a) {
      const int i = curved[a];
      const double hi = h[i];
      if (has_x) {
        for (int r = 0; r < nx; ++r) row[r] = d.Rx(i, r);
        const Eigen::Map<const Eigen::VectorXd> rx(row, nx);
        for (int j = 0; j < nx; ++j) out.Lxx.col(j).head(nx) += (hi * rx[j]) * rx;
        if (has_u)
          for (int j = 0; j < nu_; ++j) out.Lxu.col(j).head(nx) += (hi * d.Ru(i, j)) * rx;
      }
      if (has_u) {
        double* ru = row + (has_x ? nx : 0);
        for (int r = 0; r < nu_; ++r) ru[r] = d.Ru(i, r);
        const Eigen::Map<const Eigen::VectorXd> u(ru, nu_);
        for (int j = 0; j < nu_; ++j) out.Luu.col(j) += (hi * u[j]) * u;
      }
    }
    // The gradient over the rows with a nonzero g (inside its bounds a row has g = 0 too).
    for (int i = 0; i < m; ++i) {
      const double gi = g[i];
      if (gi == 0.0) continue;
      if (has_x)
        for (int r = 0; r < nx; ++r) out.Lx[r] += gi * d.Rx(i, r);
      if (has_u)
        for (int r = 0; r < nu_; ++r) out.Lu[r] += gi * d.Ru(i, r);
    }
    return;
  }
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
