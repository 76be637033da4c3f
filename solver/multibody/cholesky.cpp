#include "solver/multibody/cholesky.hpp"

#include <array>
#include <cstring>
#include <utility>

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

void inverseFromCholesky(const Eigen::MatrixXd& L, int n, Eigen::MatrixXd& X) {
  // The reciprocal pivots first (X's diagonal): a division inside the loop would sit on its
  // dependency chain.
  for (int j = 0; j < n; ++j) X(j, j) = 1.0 / L(j, j);
  for (int j = 0; j < n; ++j)
    for (int i = j + 1; i < n; ++i) {
      double s = 0.0;
      for (int k = j; k < i; ++k) s -= L(i, k) * X(k, j);
      X(i, j) = s * X(i, i);
    }
  // (L^-T L^-1)(i, j) = Σ_{k >= max(i, j)} X(k, i) X(k, j); the upper triangle first, so that the
  // lower one still holds L^-1 while it is read.
  for (int j = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i) {
      double s = 0.0;
      for (int k = j; k < n; ++k) s += X(k, i) * X(k, j);
      X(i, j) = s;
    }
  for (int j = 0; j < n; ++j)
    for (int i = j + 1; i < n; ++i) X(i, j) = X(j, i);
}

namespace {
// Eight, four and two doubles as one value (vector registers): GCC and Clang keep a few of these in
// registers across a loop, where a plain double[W] accumulator is kept on the stack and stored and
// reloaded at every step.
typedef double Chunk8 __attribute__((vector_size(64)));
typedef double Chunk4 __attribute__((vector_size(32)));
typedef double Chunk2 __attribute__((vector_size(16)));
template <typename V>
inline V load(const double* p) {
  V v;
  std::memcpy(&v, p, sizeof(V));
  return v;
}
template <typename V>
inline void store(double* p, const V& v) {
  std::memcpy(p, &v, sizeof(V));
}

// One row segment of NC chunks of 8 columns and R < 8 more, held in registers.
template <int NC, int R>
struct RowAcc {
  Chunk8 c[NC > 0 ? NC : 1];
  Chunk4 h;
  Chunk2 t;
  double s;
  static constexpr int kTail = 8 * NC;
  void load(const double* p, double scale) {
    for (int k = 0; k < NC; ++k) c[k] = scale * ::stride::load<Chunk8>(p + 8 * k);
    if constexpr ((R & 4) != 0) h = scale * ::stride::load<Chunk4>(p + kTail);
    if constexpr ((R & 2) != 0) t = scale * ::stride::load<Chunk2>(p + kTail + (R & 4));
    if constexpr ((R & 1) != 0) s = scale * p[kTail + (R & 6)];
  }
  void subtract(double u, const double* p) {
    for (int k = 0; k < NC; ++k) c[k] -= u * ::stride::load<Chunk8>(p + 8 * k);
    if constexpr ((R & 4) != 0) h -= u * ::stride::load<Chunk4>(p + kTail);
    if constexpr ((R & 2) != 0) t -= u * ::stride::load<Chunk2>(p + kTail + (R & 4));
    if constexpr ((R & 1) != 0) s -= u * p[kTail + (R & 6)];
  }
  void save(double* p) const {
    for (int k = 0; k < NC; ++k) ::stride::store(p + 8 * k, c[k]);
    if constexpr ((R & 4) != 0) ::stride::store(p + kTail, h);
    if constexpr ((R & 2) != 0) ::stride::store(p + kTail + (R & 4), t);
    if constexpr ((R & 1) != 0) p[kTail + (R & 6)] = s;
  }
};

// M^-1 on the columns [0, 8 NC + R) of the rows b + k stride. Both triangular solves in "pull"
// form: each row is finished in registers from the rows it depends on and stored once,
//   L^T y = b:      y_i = b_i - Σ_{k in subtree(i), k != i} L_ki y_k    (leaves to root)
//   L x = D^-1 y:   x_k = y_k / D_k - Σ_{i supports k} L_ki x_i        (root to leaves)
// which costs one load per multiply-add; the row-by-row "push" form (an axpy per pair of dofs)
// costs two loads and a store, chained through memory from one pair to the next.
template <int NC, int R>
void solveBlock(const Model& model, const Eigen::MatrixXd& U, double* b, Eigen::Index stride) {
  const std::vector<int>& parent = model.parentDof;
  const std::vector<int>& subtree = model.nvSubtree;
  const int n = model.nv;
  RowAcc<NC, R> acc;
  for (int i = n - 1; i >= 0; --i) {
    double* bi = b + i * stride;
    acc.load(bi, 1.0);
    const int end = i + subtree[i];
    for (int k = i + 1; k < end; ++k) acc.subtract(U(i, k), b + k * stride);
    acc.save(bi);
  }
  for (int k = 0; k < n; ++k) {
    double* bk = b + k * stride;
    acc.load(bk, 1.0 / U(k, k));
    for (int i = parent[k]; i >= 0; i = parent[i]) acc.subtract(U(i, k), b + i * stride);
    acc.save(bk);
  }
}

// Up to 64 columns per sweep with AVX-512's 32 registers (on talos_reduced 2x faster than 32
// columns: the 8 independent multiply-add chains cover latency times throughput), 32 with 16.
#ifdef __AVX512F__
constexpr int kMaxChunks = 8;
#else
constexpr int kMaxChunks = 4;
#endif
using BlockSolver = void (*)(const Model&, const Eigen::MatrixXd&, double*, Eigen::Index);
template <int NC, int... R>
constexpr std::array<BlockSolver, 8> tailSolvers(std::integer_sequence<int, R...>) {
  return {&solveBlock<NC, R>...};
}
// kSolvers[NC][R]: blocks of NC chunks (enough independent chains to hide the multiply-add
// latency, few enough to stay in registers) plus the last R columns.
template <int... NC>
constexpr std::array<std::array<BlockSolver, 8>, sizeof...(NC)> allSolvers(
    std::integer_sequence<int, NC...>) {
  return {tailSolvers<NC>(std::make_integer_sequence<int, 8>())...};
}
constexpr auto kSolvers = allSolvers(std::make_integer_sequence<int, kMaxChunks + 1>());
}  // namespace

void solveMassMatrix(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> x) {
  if (x.size() != model.nv) throwSizeError("solveMassMatrix", "x", model.nv, x.size());
  solveBlock<0, 1>(model, data.Ltdl, x.data(), 1);  // one column: rows of one entry
}

void solveMassMatrixRows(const Model& model, const Data& data, Eigen::Ref<RowMatrixXd> B) {
  if (B.rows() != model.nv) throwSizeError("solveMassMatrixRows", "B (rows)", model.nv, B.rows());
  const Eigen::Index m = B.cols(), stride = B.outerStride();
  if (m == 0) return;
  double* b = B.data();
  // Each block is one latency-bound sweep over the tree: full blocks, then the remaining chunks
  // and the columns past the last chunk together in the last one.
  Eigen::Index chunks = m / 8;
  const int tail = static_cast<int>(m % 8);
  while (chunks > kMaxChunks || (chunks == kMaxChunks && tail > 0)) {
    kSolvers[kMaxChunks][0](model, data.Ltdl, b, stride);
    b += 8 * kMaxChunks;
    chunks -= kMaxChunks;
  }
  kSolvers[static_cast<size_t>(chunks)][static_cast<size_t>(tail)](model, data.Ltdl, b, stride);
}

}  // namespace stride
