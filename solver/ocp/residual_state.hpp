#pragma once
// Residuals on the state and the control: tracking a reference state or control, and the joint
// position and velocity limits. Their Jacobians are the identity or a selection (the state
// residual's has one dense 6 x 6 block for a free-flyer), so each overrides addGaussNewton with
// the O(n) product instead of the dense one.

#include "solver/ocp/activation.hpp"
#include "solver/ocp/residual.hpp"

namespace stride {

// r = x ⊖ x_ref = [q ⊖ q_ref; v - v_ref] (dim 2nv, q ⊖ q_ref = difference(q_ref, q)).
// Rx = [∂(q ⊖ q_ref)/∂q, 0; 0, I]: the identity except a free-flyer's 6 x 6 Jlog6 block.
class StateResidual : public Residual {
 public:
  // Reference: the neutral configuration at rest.
  StateResidual(const Model& model, int nu);
  // Throws std::invalid_argument when x_ref is not of size nq + nv.
  StateResidual(const Model& model, int nu, const Eigen::VectorXd& x_ref);

  // In place, no allocation. Throws std::invalid_argument for a wrong size.
  void setReference(const Eigen::Ref<const Eigen::VectorXd>& x_ref);
  const Eigen::VectorXd& reference() const { return x_ref_; }

  std::unique_ptr<ResidualData> createData() const override;
  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void addGaussNewton(const ResidualData& d, const Eigen::Ref<const Eigen::VectorXd>& g,
                      const Eigen::Ref<const Eigen::VectorXd>& h,
                      CostDerivatives& out) const override;

 private:
  int nq_;
  bool free_flyer_;
  Eigen::VectorXd x_ref_;
};

// r = u - u_ref (dim nu), Ru = I.
class ControlResidual : public Residual {
 public:
  // Reference: zero.
  ControlResidual(const Model& model, int nu);
  // Throws std::invalid_argument when u_ref is not of size nu.
  ControlResidual(const Model& model, int nu, const Eigen::VectorXd& u_ref);

  void setReference(const Eigen::Ref<const Eigen::VectorXd>& u_ref);
  const Eigen::VectorXd& reference() const { return u_ref_; }

  std::unique_ptr<ResidualData> createData() const override;
  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void addGaussNewton(const ResidualData& d, const Eigen::Ref<const Eigen::VectorXd>& g,
                      const Eigen::Ref<const Eigen::VectorXd>& h,
                      CostDerivatives& out) const override;

 private:
  Eigen::VectorXd u_ref_;
};

// r = [joint positions; joint rates] of the 1-dof joints (a free-flyer's 7 / 6 entries skipped),
// dim 2 nj with nj = nv - 6 (free-flyer) or nv. Meant for the bounds activation of activation().
// Rx is a selection of columns.
class JointLimitResidual : public Residual {
 public:
  JointLimitResidual(const Model& model, int nu);

  int nj() const { return nj_; }
  // Bounds activation from the model's limits: lowerPositionLimit / upperPositionLimit on the
  // positions, ±velocityLimit on the rates (infinite where the model has no limit), scaled by
  // `margin` in (0, 1] towards the middle of each finite interval to keep a safety distance.
  static Activation activation(const Model& model, double weight = 1.0, double margin = 1.0);

  std::unique_ptr<ResidualData> createData() const override;
  void calc(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ResidualData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void addGaussNewton(const ResidualData& d, const Eigen::Ref<const Eigen::VectorXd>& g,
                      const Eigen::Ref<const Eigen::VectorXd>& h,
                      CostDerivatives& out) const override;

 private:
  int nj_;
  int q_offset_, v_offset_;  // first 1-dof entry in q and in v (7 / 6 with a free-flyer, else 0)
};

}  // namespace stride
