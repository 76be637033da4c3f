#include "solver/ocp/residual_contact.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace stride {

int forceOffset(const ContactSet& contacts, int contact) {
  if (contact < 0 || contact >= contacts.size() || !contacts.isActive(contact)) return -1;
  int offset = 0;
  for (int c = 0; c < contact; ++c)
    if (contacts.isActive(c)) offset += contacts[c].dim;
  return offset;
}

// ---------------------------------------------------------------- ContactResidual

namespace {
int contactDimension(const ContactSet& contacts, const std::string& contact, const char* who) {
  const int c = contacts.find(contact);
  if (c < 0)
    throw std::invalid_argument(std::string(who) + ": the contact set has no contact '" + contact +
                                "'");
  return contacts[c].dim;
}
}  // namespace

ContactResidual::ContactResidual(const Model& model, int nu, const ContactSet& contacts,
                                 const std::string& contact, int dim, const char* who)
    : Residual(dim, model.nv, nu, Dependence::StateControl),
      contact_(contact),
      contact_dim_(contactDimension(contacts, contact, who)) {}

int ContactResidual::offset(const KnotContext& ctx) const {
  if (!ctx.contacts || !ctx.forces) return -1;
  const int c = ctx.contacts->find(contact_);
  if (c < 0) return -1;
  if ((*ctx.contacts)[c].dim != contact_dim_)
    throw std::invalid_argument("ContactResidual: contact '" + contact_ +
                                "' has another dimension at this knot than at construction");
  return forceOffset(*ctx.contacts, c);
}

// ---------------------------------------------------------------- ContactForceResidual

ContactForceResidual::ContactForceResidual(const Model& model, int nu, const ContactSet& contacts,
                                           const std::string& contact,
                                           const Eigen::VectorXd& reference)
    : ContactResidual(model, nu, contacts, contact,
                      contactDimension(contacts, contact, "ContactForceResidual"),
                      "ContactForceResidual"),
      reference_(Eigen::VectorXd::Zero(contactDim())) {
  if (reference.size() != 0) setReference(reference);
}

void ContactForceResidual::setReference(const Eigen::Ref<const Eigen::VectorXd>& reference) {
  if (reference.size() != reference_.size())
    throw std::invalid_argument("ContactForceResidual: reference of size " +
                                std::to_string(reference.size()) + " for contact '" + contact() +
                                "' of dimension " + std::to_string(reference_.size()));
  reference_ = reference;
}

void ContactForceResidual::calc(ResidualData& d, const KnotContext& ctx,
                                const Eigen::Ref<const Eigen::VectorXd>&,
                                const Eigen::Ref<const Eigen::VectorXd>&) const {
  const int off = offset(ctx);
  if (off < 0) {
    d.r.setZero();
    return;
  }
  d.r = ctx.forces->segment(off, dim()) - reference_;
}

void ContactForceResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                    const Eigen::Ref<const Eigen::VectorXd>&,
                                    const Eigen::Ref<const Eigen::VectorXd>&) const {
  const int off = offset(ctx);
  if (off < 0 || !ctx.Gx || !ctx.Gu) {
    d.Rx.setZero();
    d.Ru.setZero();
    return;
  }
  d.Rx = ctx.Gx->middleRows(off, dim());
  d.Ru = ctx.Gu->middleRows(off, dim());
}

// ---------------------------------------------------------------- FrictionConeResidual

FrictionConeResidual::FrictionConeResidual(const Model& model, int nu, const ContactSet& contacts,
                                           const std::string& contact, double mu,
                                           const Eigen::Matrix3d& R_surface,
                                           double min_normal_force)
    : ContactResidual(model, nu, contacts, contact, 5, "FrictionConeResidual"),
      mu_(1.0),
      R_surface_(Eigen::Matrix3d::Identity()),
      min_force_(0.0) {
  setFriction(mu);
  setSurfaceRotation(R_surface);
  setMinimumNormalForce(min_normal_force);
}

Activation FrictionConeResidual::activation(double weight) {
  return Activation::bounds(Eigen::VectorXd::Constant(5, -std::numeric_limits<double>::infinity()),
                            Eigen::VectorXd::Zero(5), weight);
}

void FrictionConeResidual::setFriction(double mu) {
  if (!(mu > 0.0) || !std::isfinite(mu))
    throw std::invalid_argument("FrictionConeResidual: contact '" + contact() +
                                "': the friction coefficient must be positive and finite");
  mu_ = mu;
  updateRows();
}

void FrictionConeResidual::setSurfaceRotation(const Eigen::Matrix3d& R_surface) {
  if (!R_surface.allFinite() ||
      !(R_surface.transpose() * R_surface).isApprox(Eigen::Matrix3d::Identity(), 1e-9) ||
      R_surface.determinant() < 0.0)
    throw std::invalid_argument("FrictionConeResidual: contact '" + contact() +
                                "': the surface orientation is not a rotation");
  R_surface_ = R_surface;
  updateRows();
}

void FrictionConeResidual::setMinimumNormalForce(double min_normal_force) {
  if (!(min_normal_force >= 0.0) || !std::isfinite(min_normal_force))
    throw std::invalid_argument("FrictionConeResidual: contact '" + contact() +
                                "': the minimum normal force must be finite and non-negative");
  min_force_ = min_normal_force;
}

void FrictionConeResidual::updateRows() {
  const double m = mu_ / std::sqrt(2.0);
  Eigen::Matrix<double, 5, 3> As;  // in the surface frame
  As << 1, 0, -m,                  //
      -1, 0, -m,                   //
      0, 1, -m,                    //
      0, -1, -m,                   //
      0, 0, -1;
  A_.noalias() = As * R_surface_.transpose();
}

void FrictionConeResidual::calc(ResidualData& d, const KnotContext& ctx,
                                const Eigen::Ref<const Eigen::VectorXd>&,
                                const Eigen::Ref<const Eigen::VectorXd>&) const {
  // The linear part leads a 6D contact's wrench [force; moment].
  if (linearRows(d, ctx, A_)) d.r[4] += min_force_;
}

void FrictionConeResidual::calcDiff(ResidualData& d, const KnotContext& ctx,
                                    const Eigen::Ref<const Eigen::VectorXd>&,
                                    const Eigen::Ref<const Eigen::VectorXd>&) const {
  linearRowsDiff(d, ctx, A_);
}

}  // namespace stride
