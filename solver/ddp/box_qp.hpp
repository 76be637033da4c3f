#pragma once
// min ½ xᵀ H x + gᵀ x subject to lb ≤ x ≤ ub, by projected Newton (Bertsekas 1982, as used for
// control-limited DDP by Tassa, Mansard & Todorov 2014): Newton steps on the free variables, a
// projected backtracking line search, until the clamped set settles. The factor of H restricted to
// the free set is kept for the feedback gains. Workspaces are sized once.

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace stride {

class BoxQP {
 public:
  explicit BoxQP(int n);

  // x is the warm start on entry (clamped first) and the solution on exit; the size is H's, at
  // most the constructor's n. False when H restricted to the free set is not positive definite.
  bool solve(const Eigen::Ref<const Eigen::MatrixXd>& H, const Eigen::Ref<const Eigen::VectorXd>& g,
             const Eigen::Ref<const Eigen::VectorXd>& lb,
             const Eigen::Ref<const Eigen::VectorXd>& ub, Eigen::Ref<Eigen::VectorXd> x);

  int nfree() const { return nfree_; }
  const Eigen::VectorXi& freeIndices() const { return free_; }  // first nfree() entries
  // X_F <- H_FF^-1 X_F for the rows X_F of the free set (X has nfree() rows).
  template <typename Derived>
  void solveFree(Eigen::MatrixBase<Derived>& X) const {
    const auto L = Hff_.topLeftCorner(nfree_, nfree_).triangularView<Eigen::Lower>();
    L.solveInPlace(X);
    L.adjoint().solveInPlace(X);
  }
  // The Cholesky factor of H restricted to the free set (lower triangle of the top-left
  // nfree() x nfree() block), e.g. to form its inverse for many right-hand sides.
  const Eigen::MatrixXd& freeFactor() const { return Hff_; }
  int iterations() const { return iterations_; }

 private:
  bool factorFree(const Eigen::Ref<const Eigen::MatrixXd>& H);
  double objective(const Eigen::Ref<const Eigen::MatrixXd>& H,
                   const Eigen::Ref<const Eigen::VectorXd>& g,
                   const Eigen::Ref<const Eigen::VectorXd>& x);

  int n_, nfree_ = 0, iterations_ = 0;
  Eigen::VectorXi free_;
  Eigen::MatrixXd Hff_;
  Eigen::VectorXd grad_, dx_, xtry_, Hx_, rhs_;
  Eigen::VectorXd xcur_;
};

}  // namespace stride
