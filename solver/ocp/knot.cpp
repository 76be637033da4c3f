#include "solver/ocp/knot.hpp"

#include <limits>

#include <omp.h>

#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"

namespace stride {

namespace {
constexpr double kInfinity = std::numeric_limits<double>::infinity();

KnotStatus knotStatus(ContactStatus s) {
  return s == ContactStatus::NonFinite ? KnotStatus::NonFinite : KnotStatus::DynamicsFailure;
}
}  // namespace

KnotActionData::KnotActionData(const Model& model, const ContactSet& contacts,
                               const CostModel& costs)
    : ActionData(model.nq + model.nv, 2 * model.nv, actuatedDimension(model)),
      data(model),
      knot(model, contacts),
      costs(costs.createData()),
      v(Eigen::VectorXd::Zero(model.nv)) {}

SharedWorkspace::SharedWorkspace(const Model& model, int threads) {
  for (int t = 0; t < std::max(threads, 1); ++t) data_.push_back(std::make_unique<Data>(model));
}

KnotModel::KnotModel(const Model& model, const ContactSet& contacts, double dt,
                     std::shared_ptr<SharedWorkspace> workspace)
    : ActionModel(StateSpace(model), actuatedDimension(model)),
      model_(model),
      contacts_(contacts),
      costs_(model.nv, actuatedDimension(model)),
      dt_(dt),
      workspace_(std::move(workspace)) {}

Data& KnotModel::workspace(KnotActionData& d) const {
  const int thread = omp_get_thread_num();
  return workspace_ && thread < workspace_->threads() ? workspace_->forThread(thread) : d.data;
}

std::unique_ptr<ActionData> KnotModel::createData() const {
  return std::make_unique<KnotActionData>(model_, contacts_, costs_);
}

KnotContext KnotModel::context(KnotActionData& d, Data& data) const {
  const bool impulse = mode_ == KnotMode::Impulse;
  return KnotContext{model_,     data,
                     &contacts_, impulse ? &d.knot.contact.impulses : &d.knot.contact.lambda,
                     &d.knot.Gx, &d.knot.Gu};
}

// The dynamics of the knot's mode; false (with the status set, the state held and the cost
// infinite) when they cannot be solved.
bool KnotModel::dynamics(KnotActionData& d, Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                         const Eigen::Ref<const Eigen::VectorXd>& u, bool derivatives) const {
  const int nq = model_.nq, nv = model_.nv;
  const auto q = x.head(nq);
  const auto v = x.tail(nv);
  KnotData& kd = d.knot;
  ContactStatus s;
  if (mode_ == KnotMode::Contact) {
    s = derivatives ? knotDynamicsDerivatives(model_, data, contacts_, kd, q, v, u, dt_, damping)
                    : knotDynamics(model_, data, contacts_, kd, q, v, u, dt_, damping);
    if (s == ContactStatus::Ok) {
      d.x_next.head(nq) = kd.q_next;
      d.x_next.tail(nv) = kd.v_next;
      if (derivatives) {
        // Swapped, not copied: knotDynamicsDerivatives rewrites every entry of kd.Fx, kd.Fu on each
        // call, so the two buffers can trade places (O(1), no allocation).
        d.Fx.swap(kd.Fx);
        d.Fu.swap(kd.Fu);
        EulerStructure& e = d.euler;
        e.valid = true;
        e.dt = dt_;
        e.nb = model_.hasFreeFlyer() ? 6 : 0;
        if (e.nb) {
          e.Jq = kd.Jq.topLeftCorner<6, 6>();
          e.Jv = kd.Jv.topLeftCorner<6, 6>();
        }
        e.a_q = &kd.contact.ddq_dq;
        e.a_v = &kd.contact.ddq_dv;
        e.a_tau = &kd.contact.ddq_dtau;
      }
    }
  } else {
    ContactData& cd = kd.contact;
    s = derivatives
            ? impulseDynamicsDerivatives(model_, data, contacts_, cd, q, v, restitution, damping)
            : impulseDynamics(model_, data, contacts_, cd, q, v, restitution, damping);
    if (s == ContactStatus::Ok) {
      d.x_next.head(nq) = q;
      d.x_next.tail(nv) = cd.v_after;
      // Velocities for the cost's kinematics (the impulse solve only needs placements).
      forwardKinematics(model_, data, q, v);
      if (derivatives) {
        // x⁺ = (q, v⁺(q, v⁻)): the configuration passes through.
        d.euler.valid = false;
        d.Fx.setZero();
        d.Fx.topLeftCorner(nv, nv).setIdentity();
        d.Fx.bottomLeftCorner(nv, nv) = cd.ddq_dq;
        d.Fx.bottomRightCorner(nv, nv) = cd.ddq_dv;
        d.Fu.setZero();
        const int nc = cd.nc;
        kd.Gx.topLeftCorner(nc, nv) = cd.lambda_dq.topRows(nc);
        kd.Gx.topRightCorner(nc, nv) = cd.lambda_dv.topRows(nc);
        kd.Gu.topRows(nc).setZero();
      }
    }
  }
  d.contact_status = s;
  if (s != ContactStatus::Ok) {
    d.status = knotStatus(s);
    d.x_next = x;
    d.cost = kInfinity;
    return false;
  }
  d.status = KnotStatus::Ok;
  return true;
}

void KnotModel::calc(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                     const Eigen::Ref<const Eigen::VectorXd>& u) const {
  auto& d = static_cast<KnotActionData&>(data);
  Data& work = workspace(d);
  if (!dynamics(d, work, x, u, false)) return;
  d.cost = costs_.calc(d.costs, context(d, work), x, u);
  if (!std::isfinite(d.cost)) {
    d.status = KnotStatus::NonFinite;
    d.cost = kInfinity;
  }
}

void KnotModel::calcDiff(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                         const Eigen::Ref<const Eigen::VectorXd>& u) const {
  auto& d = static_cast<KnotActionData&>(data);
  Data& work = workspace(d);
  if (!dynamics(d, work, x, u, true)) return;
  d.cost = costs_.calcDiff(d.costs, context(d, work), x, u, d.Lx, d.Lu, d.Lxx, d.Lxu, d.Luu);
  if (!std::isfinite(d.cost) || !d.Lx.allFinite() || !d.Lu.allFinite()) {
    d.status = KnotStatus::NonFinite;
    d.cost = kInfinity;
  }
}

TerminalActionData::TerminalActionData(const Model& model, const CostModel& costs)
    : ActionData(model.nq + model.nv, 2 * model.nv, 0), data(model), costs(costs.createData()) {}

TerminalModel::TerminalModel(const Model& model)
    : ActionModel(StateSpace(model), 0), model_(model), costs_(model.nv, 0) {}

std::unique_ptr<ActionData> TerminalModel::createData() const {
  return std::make_unique<TerminalActionData>(model_, costs_);
}

namespace {
bool terminalKinematics(const Model& model, TerminalActionData& d,
                        const Eigen::Ref<const Eigen::VectorXd>& x) {
  if (!x.allFinite()) {
    d.status = KnotStatus::NonFinite;
    d.cost = kInfinity;
    return false;
  }
  forwardKinematics(model, d.data, x.head(model.nq), x.tail(model.nv));
  updateJointJacobians(model, d.data);
  d.status = KnotStatus::Ok;
  return true;
}
}  // namespace

void TerminalModel::calc(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                         const Eigen::Ref<const Eigen::VectorXd>& u) const {
  auto& d = static_cast<TerminalActionData&>(data);
  if (!terminalKinematics(model_, d, x)) return;
  d.cost = costs_.calc(d.costs, KnotContext{model_, d.data}, x, u);
  if (!std::isfinite(d.cost)) {
    d.status = KnotStatus::NonFinite;
    d.cost = kInfinity;
  }
}

void TerminalModel::calcDiff(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                             const Eigen::Ref<const Eigen::VectorXd>& u) const {
  auto& d = static_cast<TerminalActionData&>(data);
  if (!terminalKinematics(model_, d, x)) return;
  d.cost =
      costs_.calcDiff(d.costs, KnotContext{model_, d.data}, x, u, d.Lx, d.Lu, d.Lxx, d.Lxu, d.Luu);
  if (!std::isfinite(d.cost) || !d.Lx.allFinite()) {
    d.status = KnotStatus::NonFinite;
    d.cost = kInfinity;
  }
}

}  // namespace stride
