#pragma once
// Tree-sparse factorization of the joint-space inertia matrix, M = L^T D L (Featherstone, RBDA
// §6.5): L is unit lower triangular and, like M, nonzero only where the column's dof supports the
// row's, so factorization and solves cost O(n d) and O(n d^2) (d: depth of the tree) instead of
// the dense O(n^3) and O(n^2). Stored in data.Ltdl, upper triangle: Ltdl(i, k) = L(k, i), D on the
// diagonal.

#include "solver/multibody/data.hpp"

namespace stride {

// Factorizes data.M (crba first) into data.Ltdl. Returns false when M is not positive definite
// (a moving body without inertia, or non-finite input): the factor is then unusable.
bool factorizeMassMatrix(const Model& model, Data& data);
// x <- M^-1 x, with the factorization in data.Ltdl.
void solveMassMatrix(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> x);
// B <- M^-1 B for a row-major block: each step of the solve is an operation on whole rows,
// contiguous in memory, so many right-hand sides vectorize together. The fast path for matrices.
void solveMassMatrixRows(const Model& model, const Data& data, Eigen::Ref<RowMatrixXd> B);

// A^-1 (n x n, the top-left of X) of a small dense SPD matrix A from its Cholesky factor L (lower
// triangle of the top-left n x n of L): L^-1 by forward substitution, then A^-1 = L^-T L^-1. Plain
// loops: at a dozen rows Eigen's blocked triangular solves spend more time in their setup than in
// the arithmetic. For the contact Schur complement (contact_dynamics.cpp) and the Riccati pass's
// Quu (solver/ddp/backward_pass.cpp), whose products with the inverse beat solves at these sizes.
void inverseFromCholesky(const Eigen::MatrixXd& L, int n, Eigen::MatrixXd& X);

}  // namespace stride
