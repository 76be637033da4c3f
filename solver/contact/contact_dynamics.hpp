#pragma once
// Rigid contact dynamics (paper §IV, eq. 10), the KKT system
//   [M  Jc^T] [ v̇ ]   [ τ - b ]
//   [Jc  0  ] [-λ ] = [  -γ   ]
// solved through the tree-sparse factorization of M and the Cholesky factorization of the Schur
// complement K = Jc M^-1 Jc^T (+ μ I, the paper's damping for rank-deficient contact sets), and
// the impulse at touch-down
//   [M  Jc^T] [ v⁺ ]   [ M v⁻ ]
//   [Jc  0  ] [-Λ  ] = [ -r Jc v⁻ ]   (r: restitution, 0 = perfectly inelastic).
// Derivatives come from differentiating the KKT system at the solution, reusing both
// factorizations (the KKT matrix is never inverted): with R_x = ∂(RNEA(q, v, v̇) - Jc^T λ)/∂x and
// A_x = ∂(constraint acceleration)/∂x,
//   ∂λ/∂x = K^-1 (Jc M^-1 R_x - A_x),   ∂v̇/∂x = M^-1 (-R_x + Jc^T ∂λ/∂x),
//   ∂λ/∂τ = -K^-1 Jc M^-1,             ∂v̇/∂τ = M^-1 (I + Jc^T ∂λ/∂τ).

#include <vector>

#include "solver/contact/contact_set.hpp"
#include "solver/multibody/data.hpp"

namespace stride {

enum class ContactStatus : std::uint8_t {
  Ok,
  NonFinite,  // an input (q, v, τ) is not finite; outputs are left zero
  Singular,   // K is (numerically) singular: rank-deficient contacts without damping; outputs zero
  SingularMassMatrix,  // M is not positive definite (a moving body without inertia); outputs zero
};
const char* toString(ContactStatus status);

// Workspace for one contact set, sized for all its contacts (any active subset fits). Built after
// the set is complete: a set that grows afterwards is refused at the next call
// (std::invalid_argument).
struct ContactData {
  ContactData(const Model& model, const ContactSet& contacts);

  int nc = 0;                // active dimension of the last call
  Eigen::MatrixXd Jc;        // maxNc x nv, LOCAL rows of the active contacts (top nc rows)
  Eigen::VectorXd gamma;     // drift γ (constraint acceleration at v̇ = 0)
  Eigen::VectorXd lambda;    // contact forces, in each contact's force frame
  Eigen::VectorXd ddq;       // v̇
  Eigen::VectorXd v_after;   // impulse: v⁺
  Eigen::VectorXd impulses;  // impulse: Λ, in each contact's force frame

  // Derivatives (tangent space). Contact dynamics: of v̇ and λ; impulse: of v⁺ and Λ, with the
  // *_dv blocks taken with respect to v⁻ and no *_dtau.
  Eigen::MatrixXd ddq_dq, ddq_dv, ddq_dtau;           // nv x nv
  Eigen::MatrixXd lambda_dq, lambda_dv, lambda_dtau;  // maxNc x nv

  // Workspaces.
  Eigen::VectorXd rhs, zero;
  Eigen::MatrixXd Yt;                // Jc M^-1, maxNc x nv
  Eigen::MatrixXd K;                 // Schur complement, maxNc x maxNc (factorized in place)
  Eigen::MatrixXd dacc_dq, dacc_dv;  // constraint acceleration (or velocity) derivatives
  RowMatrixXd rhs3;                  // nv x 3nv, right-hand sides of the primal derivatives
  Eigen::MatrixXd work;              // maxNc x 3nv
  Eigen::MatrixXd Kinv;              // K^-1 (derivatives only)
  RowMatrixXd dual_rows;             // maxNc x 3nv, ∂λ/∂x row by row
  Matrix6Xd Jframe, dv_dq, dv_dv, da_dq, da_dv;
  Eigen::Matrix3Xd rows3;
  std::vector<Vector6d> fext;  // contact forces as joint wrenches
};

// v̇ and λ (cdata.ddq, cdata.lambda) for torque τ; also cdata.Jc, cdata.gamma, data.M.
ContactStatus contactDynamics(const Model& model, Data& data, const ContactSet& contacts,
                              ContactData& cdata, const Eigen::Ref<const Eigen::VectorXd>& q,
                              const Eigen::Ref<const Eigen::VectorXd>& v,
                              const Eigen::Ref<const Eigen::VectorXd>& tau, double damping = 0.0);
// contactDynamics, then the derivatives of v̇ and λ with respect to q, v and τ.
ContactStatus contactDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         ContactData& cdata,
                                         const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         const Eigen::Ref<const Eigen::VectorXd>& tau,
                                         double damping = 0.0);
// Where the derivatives of v̇ go: into cdata.ddq_dq, ddq_dv, ddq_dtau (Matrices), or left as the
// rows the solve with M produced (Rows): cdata.rhs3 (row-major) then holds
// [∂v̇/∂q | ∂v̇/∂v | ∂v̇/∂τ columns tau_first..nv-1] side by side, and the three matrices are not
// written. The knot reads the rows directly into its Jacobians: the copy to column-major
// matrices, a strided scalar loop, was ~2% of a solo knot.
enum class PrimalDerivatives : std::uint8_t { Matrices, Rows };
// The same with the τ derivatives restricted to the columns [tau_first, nv) of cdata.ddq_dtau and
// cdata.lambda_dtau (their other columns are left as they were): the knot needs only the actuated
// columns, ∂/∂u = ∂/∂τ [0; I], and each column costs a solve with M.
ContactStatus contactDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         ContactData& cdata,
                                         const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         const Eigen::Ref<const Eigen::VectorXd>& tau,
                                         double damping, int tau_first,
                                         PrimalDerivatives primal = PrimalDerivatives::Matrices);
// Only the derivatives part of contactDynamicsDerivatives, at the solution that contactDynamics
// (same q, v, τ, damping) has just left in data and cdata: what it reads there is the kinematics
// (data.oMi, J, oYbody), the factor of M (data.Ltdl), the constraint rows and Schur factor
// (cdata.nc, Jc, Yt, K) and the solution (cdata.ddq, lambda). A knot whose calc kept those
// (KnotModel::calcDiff) skips the solve this way.
void contactDynamicsDerivativesAtSolution(const Model& model, Data& data,
                                          const ContactSet& contacts, ContactData& cdata,
                                          const Eigen::Ref<const Eigen::VectorXd>& v, int tau_first,
                                          PrimalDerivatives primal = PrimalDerivatives::Matrices);

// v⁺ and Λ (cdata.v_after, cdata.impulses) when the active contacts close at velocity v⁻.
ContactStatus impulseDynamics(const Model& model, Data& data, const ContactSet& contacts,
                              ContactData& cdata, const Eigen::Ref<const Eigen::VectorXd>& q,
                              const Eigen::Ref<const Eigen::VectorXd>& v_before,
                              double restitution = 0.0, double damping = 0.0);
// impulseDynamics, then the derivatives of v⁺ and Λ with respect to q and v⁻.
ContactStatus impulseDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         ContactData& cdata,
                                         const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v_before,
                                         double restitution = 0.0, double damping = 0.0);

}  // namespace stride
