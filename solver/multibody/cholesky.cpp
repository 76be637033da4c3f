#include "solver/multibody/cholesky.hpp"

namespace stride {

bool factorizeMassMatrix(const Model& model, Data& data) {
  Eigen::MatrixXd& U = data.Ltdl;
  U = data.M;
  const std::vector<int>& parent = model.parentDof;
  // RBDA Table 6.3 (LTDL), on the transpose so that each column is read top-down.
  for (int k = model.nv - 1; k >= 0; --k) {
    if (!(U(k, k) > 0.0)) return false;  // also catches NaN
    for (int i = parent[k]; i >= 0; i = parent[i]) {
      const double a = U(i, k) / U(k, k);
      for (int j = i; j >= 0; j = parent[j]) U(j, i) -= a * U(j, k);
      U(i, k) = a;
    }
  }
  return true;
}

namespace {
void solveInPlace(const Model& model, const Data& data, double* x) {
  const Eigen::MatrixXd& U = data.Ltdl;
  const std::vector<int>& parent = model.parentDof;
  const int n = model.nv;
  // L^T y = b: leaves to root.
  for (int k = n - 1; k >= 0; --k)
    for (int i = parent[k]; i >= 0; i = parent[i]) x[i] -= U(i, k) * x[k];
  for (int k = 0; k < n; ++k) x[k] /= U(k, k);
  // L x = z: root to leaves.
  for (int k = 0; k < n; ++k)
    for (int i = parent[k]; i >= 0; i = parent[i]) x[k] -= U(i, k) * x[i];
}
}  // namespace

void solveMassMatrix(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> x) {
  if (x.size() != model.nv) throwSizeError("solveMassMatrix", "x", model.nv, x.size());
  solveInPlace(model, data, x.data());
}

void solveMassMatrixRows(const Model& model, const Data& data, Eigen::Ref<RowMatrixXd> B) {
  if (B.rows() != model.nv) throwSizeError("solveMassMatrixRows", "B (rows)", model.nv, B.rows());
  const Eigen::MatrixXd& U = data.Ltdl;
  const std::vector<int>& parent = model.parentDof;
  const int n = model.nv;
  const Eigen::Index m = B.cols(), stride = B.outerStride();
  double* b = B.data();
  // Plain loops over contiguous rows: the compiler vectorizes them without the per-call cost of
  // Eigen's dynamic-size row expressions (rows are short: nc to 3 nv entries). Blocking the
  // columns to stay in L1 was measured and did not help at these sizes.
  auto axpy = [m](double a, const double* x, double* y) {
    for (Eigen::Index c = 0; c < m; ++c) y[c] -= a * x[c];
  };
  for (int k = n - 1; k >= 0; --k)
    for (int i = parent[k]; i >= 0; i = parent[i]) axpy(U(i, k), b + k * stride, b + i * stride);
  for (int k = 0; k < n; ++k) {
    const double d = 1.0 / U(k, k);
    double* row = b + k * stride;
    for (Eigen::Index c = 0; c < m; ++c) row[c] *= d;
  }
  for (int k = 0; k < n; ++k)
    for (int i = parent[k]; i >= 0; i = parent[i]) axpy(U(i, k), b + i * stride, b + k * stride);
}

}  // namespace stride
