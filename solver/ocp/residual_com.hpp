#pragma once
// Whole-body residuals: the centre of mass and the centroidal momentum. Both are computed from
// the knot's kinematics (data.oMi, data.v, data.J) by one composite sweep in the residual's own
// workspace, so the knot's Data (its CRBA fields in particular) is left untouched.

#include <vector>

#include "solver/ocp/residual.hpp"

namespace stride {

// r = com - c_ref (dim 3, world), Rx = [Jcom, 0]. Both residuals throw std::invalid_argument for
// a model without moving mass.
class ComPositionResidual : public Residual {
 public:
  ComPositionResidual(const Model& model, int nu,
                      const Eigen::Vector3d& reference = Eigen::Vector3d::Zero());
  void setReference(const Eigen::Vector3d& reference) { reference_ = reference; }
  const Eigen::Vector3d& reference() const { return reference_; }

  std::unique_ptr<ResidualData> createData() const override;
  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  int njoints_;
  Eigen::Vector3d reference_;
};

// r = h_g - h_ref (dim 6): the centroidal momentum [linear; angular about the CoM] in world axes,
// h_g = A_g(q) v. Rx = [∂h_g/∂q, A_g].
class CentroidalMomentumResidual : public Residual {
 public:
  CentroidalMomentumResidual(const Model& model, int nu,
                             const Vector6d& reference = Vector6d::Zero());
  void setReference(const Vector6d& reference) { reference_ = reference; }
  const Vector6d& reference() const { return reference_; }

  std::unique_ptr<ResidualData> createData() const override;
  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  int njoints_;
  Vector6d reference_;
};

// Workspace of both: per joint, the composite (subtree) inertia and momentum in the world frame,
// and the joint's world spatial velocity.
struct ComResidualData : ResidualData {
  ComResidualData(int dim, int ndx, int nu, int njoints);
  std::vector<Inertia> Ycrb;
  std::vector<Vector6d> ov, H;
  double mass = 0.0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Vector6d h = Vector6d::Zero();  // total momentum about the world origin
};

}  // namespace stride
