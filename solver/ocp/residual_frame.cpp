#include "solver/ocp/residual_frame.hpp"

#include <stdexcept>

#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {

namespace {
int lookUpFrame(const Model& model, const std::string& frame, const char* who) {
  if (!model.existFrame(frame))
    throw std::invalid_argument(std::string(who) + ": model '" + model.name + "' has no frame '" +
                                frame + "'");
  return model.getFrameId(frame);
}
}  // namespace

FrameResidual::FrameResidual(const Model& model, int nu, const std::string& frame, int dim,
                             Dependence dependence)
    : Residual(dim, model.nv, nu, dependence), frame_(lookUpFrame(model, frame, "FrameResidual")) {}

std::unique_ptr<ResidualData> FrameResidual::createData() const {
  return std::make_unique<FrameResidualData>(dim(), 2 * nv(), nu());
}

SE3 FrameResidual::placement(const KnotContext& ctx) const {
  const Frame& f = ctx.model.frames[frame_];
  return ctx.data.oMi[f.parentJoint] * f.placement;
}

// ---------------------------------------------------------------- placement

FramePlacementResidual::FramePlacementResidual(const Model& model, int nu, const std::string& frame,
                                               const SE3& reference)
    : FrameResidual(model, nu, frame, 6, Dependence::Configuration), reference_(reference) {}

void FramePlacementResidual::calc(ResidualData& d, const KnotContext& ctx,
                                  const Eigen::Ref<const Eigen::VectorXd>&,
                                  const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& fd = static_cast<FrameResidualData&>(d);
  fd.oMf = placement(ctx);
  fd.rMf = reference_.actInv(fd.oMf);
  fd.r.head<6>() = log6(fd.rMf);
}

void FramePlacementResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                      const Eigen::Ref<const Eigen::VectorXd>&,
                                      const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& fd = static_cast<FrameResidualData&>(d);
  // A tangent step moves the frame by oMf exp(J_local dq), so the log moves by Jlog6 J_local dq.
  getFrameJacobian(ctx.model, ctx.data, frame_, ReferenceFrame::Local, fd.J6);
  fd.Rx.leftCols(nv()).noalias() = Jlog6(fd.rMf) * fd.J6;
}

// ---------------------------------------------------------------- translation

FrameTranslationResidual::FrameTranslationResidual(const Model& model, int nu,
                                                   const std::string& frame,
                                                   const Eigen::Vector3d& reference)
    : FrameResidual(model, nu, frame, 3, Dependence::Configuration), reference_(reference) {
  const Joint& jt = model.joints[model.frames[this->frame()].parentJoint];
  for (int k = jt.idx_v + jt.nv - 1; k >= 0; k = model.parentDof[k]) dofs_.push_back(k);
}

void FrameTranslationResidual::calc(ResidualData& d, const KnotContext& ctx,
                                    const Eigen::Ref<const Eigen::VectorXd>&,
                                    const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& fd = static_cast<FrameResidualData&>(d);
  fd.oMf = placement(ctx);
  fd.r.head<3>() = fd.oMf.p - reference_;
}

void FrameTranslationResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                        const Eigen::Ref<const Eigen::VectorXd>&,
                                        const Eigen::Ref<const Eigen::VectorXd>&) const {
  // The translation rows of the LOCAL_WORLD_ALIGNED frame Jacobian, on the supporting columns
  // only: the velocity at the frame origin p of the world joint motion S_k is S_lin + S_ang x p.
  // (getFrameJacobian fills all six rows of every column.)
  auto& fd = static_cast<FrameResidualData&>(d);
  const Eigen::Vector3d p = fd.oMf.p;
  auto Rx = fd.Rx.leftCols(nv());
  Rx.setZero();
  for (const int k : dofs_) {
    const Eigen::Vector3d S_lin = ctx.data.J.col(k).head<3>(), S_ang = ctx.data.J.col(k).tail<3>();
    Rx.col(k).head<3>() = S_lin - p.cross(S_ang);
  }
}

void FrameTranslationResidual::addGaussNewton(const ResidualData& d,
                                              const Eigen::Ref<const Eigen::VectorXd>& g,
                                              const Eigen::Ref<const Eigen::VectorXd>& h,
                                              CostDerivatives& out) const {
  // Lx_k += R_kᵀ g and Lxx_kl += R_kᵀ diag(h) R_l on the supporting columns k, l (3-vectors).
  for (const int l : dofs_) {
    const Eigen::Vector3d Rl = d.Rx.col(l);
    out.Lx[l] += Rl.dot(g.head<3>());
    const Eigen::Vector3d hRl = h.head<3>().cwiseProduct(Rl);
    for (const int k : dofs_) out.Lxx(k, l) += d.Rx.col(k).head<3>().dot(hRl);
  }
}

// ---------------------------------------------------------------- rotation

FrameRotationResidual::FrameRotationResidual(const Model& model, int nu, const std::string& frame,
                                             const Eigen::Matrix3d& reference)
    : FrameResidual(model, nu, frame, 3, Dependence::Configuration), reference_(reference) {}

void FrameRotationResidual::calc(ResidualData& d, const KnotContext& ctx,
                                 const Eigen::Ref<const Eigen::VectorXd>&,
                                 const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& fd = static_cast<FrameResidualData&>(d);
  fd.oMf = placement(ctx);
  fd.rMf.R.noalias() = reference_.transpose() * fd.oMf.R;
  fd.r.head<3>() = log3(fd.rMf.R);
}

void FrameRotationResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                     const Eigen::Ref<const Eigen::VectorXd>&,
                                     const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& fd = static_cast<FrameResidualData&>(d);
  getFrameJacobian(ctx.model, ctx.data, frame_, ReferenceFrame::Local, fd.J6);
  fd.Rx.leftCols(nv()).noalias() = Jlog3(fd.rMf.R) * fd.J6.bottomRows<3>();
}

// ---------------------------------------------------------------- velocity

FrameVelocityResidual::FrameVelocityResidual(const Model& model, int nu, const std::string& frame,
                                             ReferenceFrame rf, const Vector6d& reference)
    : FrameResidual(model, nu, frame, 6, Dependence::State), rf_(rf), reference_(reference) {
  if (rf == ReferenceFrame::World)
    throw std::invalid_argument("FrameVelocityResidual: frame '" + frame +
                                "': the velocity is Local or LocalWorldAligned");
}

void FrameVelocityResidual::calc(ResidualData& d, const KnotContext& ctx,
                                 const Eigen::Ref<const Eigen::VectorXd>&,
                                 const Eigen::Ref<const Eigen::VectorXd>&) const {
  auto& fd = static_cast<FrameResidualData&>(d);
  const Frame& f = ctx.model.frames[frame_];
  fd.oMf = placement(ctx);
  Vector6d vf = f.placement.actInv(ctx.data.v[f.parentJoint]);
  if (rf_ == ReferenceFrame::LocalWorldAligned) {
    vf.head<3>() = fd.oMf.R * vf.head<3>();
    vf.tail<3>() = fd.oMf.R * vf.tail<3>();
  }
  fd.r.head<6>() = vf - reference_;
}

void FrameVelocityResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                     const Eigen::Ref<const Eigen::VectorXd>&,
                                     const Eigen::Ref<const Eigen::VectorXd>&) const {
  // World twists: moving dof k (axis S_k, world) carries its subtree, frame included, by exp(S_k):
  // the joint axes below k turn with it, so ov_f changes by S_k x (ov_f - ov_λ) (λ: the parent of
  // k's joint), while the frame's own motion X_f^-1 changes by -S_k x. Together
  //   ∂v_f/∂q_k = X_f^-1 (ov_λ x S_k),   ∂v_f/∂v_k = X_f^-1 S_k   (LOCAL).
  // LOCAL_WORLD_ALIGNED rotates by R_f, which turns with ω_k: one more term ω_k x (R_f v_f).
  auto& fd = static_cast<FrameResidualData&>(d);
  const Model& model = ctx.model;
  const Data& data = ctx.data;
  const int nv = this->nv();
  const Frame& f = model.frames[frame_];
  const SE3& oMf = fd.oMf;
  const bool lwa = rf_ == ReferenceFrame::LocalWorldAligned;
  Vector6d vw = Vector6d::Zero();  // the frame velocity, LOCAL_WORLD_ALIGNED
  if (lwa) {
    const Vector6d vl = f.placement.actInv(data.v[f.parentJoint]);
    vw.head<3>() = oMf.R * vl.head<3>();
    vw.tail<3>() = oMf.R * vl.tail<3>();
  }
  fd.Rx.setZero();
  for (int jj = f.parentJoint; jj > 0; jj = model.joints[jj].parent) {
    const Joint& joint = model.joints[jj];
    const Vector6d ov_parent = data.oMi[joint.parent].act(data.v[joint.parent]);
    for (int k = joint.idx_v; k < joint.idx_v + joint.nv; ++k) {
      const Vector6d S = data.J.col(k);
      Vector6d dq = oMf.actInv(motionCross(ov_parent, S));
      Vector6d dv = oMf.actInv(S);
      if (lwa) {
        const Eigen::Vector3d w = S.tail<3>();
        dq.head<3>() = oMf.R * dq.head<3>() + w.cross(vw.head<3>());
        dq.tail<3>() = oMf.R * dq.tail<3>() + w.cross(vw.tail<3>());
        dv.head<3>() = oMf.R * dv.head<3>();
        dv.tail<3>() = oMf.R * dv.tail<3>();
      }
      fd.Rx.block<6, 1>(0, k) = dq;
      fd.Rx.block<6, 1>(0, nv + k) = dv;
    }
  }
}

}  // namespace stride
