#include "solver/multibody/data.hpp"

namespace stride {

Data::Data(const Model& model) {
  const size_t n = static_cast<size_t>(model.njoints());
  const int nv = model.nv;
  liMi.assign(n, SE3::Identity());
  oMi.assign(n, SE3::Identity());
  v.assign(n, Vector6d::Zero());
  a.assign(n, Vector6d::Zero());
  oMf.assign(static_cast<size_t>(model.nframes()), SE3::Identity());
  a_gf.assign(n, Vector6d::Zero());
  f.assign(n, Vector6d::Zero());
  tau = Eigen::VectorXd::Zero(nv);
  nle = Eigen::VectorXd::Zero(nv);
  g = Eigen::VectorXd::Zero(nv);
  J = Matrix6Xd::Zero(6, nv);
  // A first factorization, so that a copied or moved Data never reads the LLT's unset
  // ComputationInfo (GCC's UBSan reports it as an invalid enum load); ABA factors it anew.
  rootLLT.compute(Matrix6d::Identity());
  oYcrb.assign(n, Inertia::Zero());
  oYbody.assign(n, Inertia::Zero());
  ov.assign(n, Vector6d::Zero());
  M = Eigen::MatrixXd::Zero(nv, nv);
  oYaba.assign(n, Matrix6d::Zero());
  of.assign(n, Vector6d::Zero());
  oc.assign(n, Vector6d::Zero());
  oa.assign(n, Vector6d::Zero());
  U = Matrix6Xd::Zero(6, nv);
  Dinv = Eigen::VectorXd::Zero(nv);
  u = Eigen::VectorXd::Zero(nv);
  ddq = Eigen::VectorXd::Zero(nv);
  oBcrb.assign(n, Inertia::Zero());
  oh.assign(n, Vector6d::Zero());
  oF.assign(n, Vector6d::Zero());
  for (Matrix6Xd* m : {&dW, &dC, &dE, &dA, &dB, &dG, &dH}) *m = Matrix6Xd::Zero(6, nv);
  dtau_dq = Eigen::MatrixXd::Zero(nv, nv);
  dtau_dv = Eigen::MatrixXd::Zero(nv, nv);
  Ltdl = Eigen::MatrixXd::Zero(nv, nv);
  Minv = Eigen::MatrixXd::Zero(nv, nv);
  ddq_dq = Eigen::MatrixXd::Zero(nv, nv);
  ddq_dv = Eigen::MatrixXd::Zero(nv, nv);
  rhs3 = RowMatrixXd::Zero(nv, 3 * nv);
  mass = model.totalMass();
  Jcom = Eigen::Matrix3Xd::Zero(3, nv);
  Ag = Matrix6Xd::Zero(6, nv);
}

}  // namespace stride
