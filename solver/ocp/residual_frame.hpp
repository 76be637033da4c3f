#pragma once
// Residuals on one frame of the model: its placement, position, orientation and spatial velocity
// against references that the controller rewrites in place. Frames are named at construction and
// looked up once. The placement is read as data.oMi[parent joint] * frame.placement (data.oMf is
// not assumed current), Jacobians from data.J.

#include <string>
#include <vector>

#include "solver/ocp/residual.hpp"

namespace stride {

// Data of the frame residuals: the frame placement of the last calc.
struct FrameResidualData : ResidualData {
  FrameResidualData(int dim, int ndx, int nu) : ResidualData(dim, ndx, nu) {}
  SE3 oMf;
  SE3 rMf;  // reference^-1 * oMf (placement residual only)
};

// Base of the frame residuals: the frame lookup and the data type.
class FrameResidual : public Residual {
 public:
  int frame() const { return frame_; }
  std::unique_ptr<ResidualData> createData() const override;

 protected:
  // Throws std::invalid_argument naming the frame when the model has no frame of that name.
  FrameResidual(const Model& model, int nu, const std::string& frame, int dim,
                Dependence dependence);
  SE3 placement(const KnotContext& ctx) const;
  int frame_;
};

// r = log6(M_ref^-1 oMf) (dim 6, [linear; angular]), Rx = [Jlog6(M_ref^-1 oMf) J_local, 0].
class FramePlacementResidual : public FrameResidual {
 public:
  FramePlacementResidual(const Model& model, int nu, const std::string& frame,
                         const SE3& reference = SE3::Identity());
  void setReference(const SE3& reference) { reference_ = reference; }
  const SE3& reference() const { return reference_; }

  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  SE3 reference_;
};

// r = p - p_ref (dim 3, world), Rx = [linear rows of the LOCAL_WORLD_ALIGNED Jacobian, 0].
class FrameTranslationResidual : public FrameResidual {
 public:
  FrameTranslationResidual(const Model& model, int nu, const std::string& frame,
                           const Eigen::Vector3d& reference = Eigen::Vector3d::Zero());
  void setReference(const Eigen::Vector3d& reference) { reference_ = reference; }
  const Eigen::Vector3d& reference() const { return reference_; }

  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  // Rx is nonzero only on the dofs supporting the frame (a foot: the base's 6 and its leg's 3 of
  // a quadruped's 18): the products run on those columns only.
  void addGaussNewton(const ResidualData& d, const Eigen::Ref<const Eigen::VectorXd>& g,
                      const Eigen::Ref<const Eigen::VectorXd>& h,
                      CostDerivatives& out) const override;

 private:
  Eigen::Vector3d reference_;
  std::vector<int> dofs_;  // the supporting dofs, set at construction
};

// r = log3(R_ref^T R) (dim 3), Rx = [Jlog3(R_ref^T R) (angular rows of J_local), 0].
class FrameRotationResidual : public FrameResidual {
 public:
  FrameRotationResidual(const Model& model, int nu, const std::string& frame,
                        const Eigen::Matrix3d& reference = Eigen::Matrix3d::Identity());
  void setReference(const Eigen::Matrix3d& reference) { reference_ = reference; }
  const Eigen::Matrix3d& reference() const { return reference_; }

  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  Eigen::Matrix3d reference_;
};

// r = v_f - v_ref (dim 6): the frame's spatial velocity [linear; angular] in LOCAL or
// LOCAL_WORLD_ALIGNED axes (velocity of the frame origin either way). Depends on q and v.
class FrameVelocityResidual : public FrameResidual {
 public:
  // Throws std::invalid_argument for ReferenceFrame::World.
  FrameVelocityResidual(const Model& model, int nu, const std::string& frame, ReferenceFrame rf,
                        const Vector6d& reference = Vector6d::Zero());
  void setReference(const Vector6d& reference) { reference_ = reference; }
  const Vector6d& reference() const { return reference_; }
  ReferenceFrame referenceFrame() const { return rf_; }

  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  ReferenceFrame rf_;
  Vector6d reference_;
};

}  // namespace stride
