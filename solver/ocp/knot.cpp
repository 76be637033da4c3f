#include "solver/ocp/knot.hpp"

#include <limits>
#include <stdexcept>

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

const char* toString(Integrator integrator) {
  return integrator == Integrator::Rk4 ? "rk4" : "euler";
}

bool parseIntegrator(const std::string& name, Integrator& out) {
  if (name == "euler")
    out = Integrator::Euler;
  else if (name == "rk4")
    out = Integrator::Rk4;
  else
    return false;
  return true;
}

KnotWorkspace::KnotWorkspace(const Model& model, const ContactSet& contacts, const CostModel& costs,
                             Integrator integrator)
    : data(model), knot(model, contacts), costs(costs.createData()) {
  if (integrator == Integrator::Rk4) rk4 = std::make_unique<Rk4Data>(model, contacts);
}

KeptSolve::KeptSolve(const Model& model, const ContactSet& contacts) {
  // The buffers as the workspace's start: they take turns in it.
  Data data(model);
  ContactData cd(model, contacts);
  x = Eigen::VectorXd::Zero(model.nq + model.nv);
  u = Eigen::VectorXd::Zero(actuatedDimension(model));
  trade(data, cd);
}

void KeptSolve::trade(Data& data, ContactData& cd) {
  std::swap(nc, cd.nc);
  oMi.swap(data.oMi);
  J.swap(data.J);
  oYbody.swap(data.oYbody);
  v.swap(data.v);
  a.swap(data.a);
  Ltdl.swap(data.Ltdl);
  Jc.swap(cd.Jc);
  Yt.swap(cd.Yt);
  K.swap(cd.K);
  ddq.swap(cd.ddq);
}

KnotActionData::KnotActionData(const Model& model, const ContactSet& contacts,
                               const CostModel& costs, int slot, Integrator integrator)
    : ActionData(model.nq + model.nv, 2 * model.nv, actuatedDimension(model)),
      forces_(Eigen::VectorXd::Zero(contacts.maxNc())),
      kept_(model, contacts),
      slot_(slot),
      integrator_(integrator) {
  if (slot < 0) own_ = std::make_unique<KnotWorkspace>(model, contacts, costs, integrator);
}

SharedWorkspace::SharedWorkspace(const Model& model, int threads)
    : model_(model), threads_(std::max(threads, 1)) {
  for (int t = 0; t < threads_; ++t) data_.push_back(std::make_unique<Data>(model));
}

namespace {
std::vector<std::pair<const std::type_info*, int>> termSignature(const CostModel& costs) {
  std::vector<std::pair<const std::type_info*, int>> terms;
  for (int i = 0; i < costs.size(); ++i) {
    const Residual& r = *costs[i].residual;
    terms.emplace_back(&typeid(r), r.dim());
  }
  return terms;
}
}  // namespace

int SharedWorkspace::reserve(const ContactSet& contacts, const CostModel& costs,
                             Integrator integrator) {
  const auto terms = termSignature(costs);
  for (size_t s = 0; s < slots_.size(); ++s) {
    const Slot& slot = slots_[s];
    // Exact match on the integrator: an Rk4 slot could serve Euler knots too, but then which slot
    // an Euler knot gets would depend on the order of setup.
    if (slot.max_nc != contacts.maxNc() || slot.integrator != integrator ||
        slot.terms.size() != terms.size())
      continue;
    bool same = true;
    for (size_t i = 0; i < terms.size() && same; ++i)
      same = *slot.terms[i].first == *terms[i].first && slot.terms[i].second == terms[i].second;
    if (same) return static_cast<int>(s);
  }
  Slot slot{contacts.maxNc(), integrator, terms, {}};
  for (int t = 0; t < threads_; ++t)
    slot.scratch.push_back(std::make_unique<KnotWorkspace>(model_, contacts, costs, integrator));
  slots_.push_back(std::move(slot));
  return static_cast<int>(slots_.size()) - 1;
}

KnotModel::KnotModel(const Model& model, const ContactSet& contacts, double dt,
                     std::shared_ptr<SharedWorkspace> workspace)
    : ActionModel(StateSpace(model), actuatedDimension(model)),
      model_(model),
      contacts_(contacts),
      costs_(model.nv, actuatedDimension(model)),
      dt_(dt),
      workspace_(std::move(workspace)) {}

int KnotModel::maxThreads() const {
  return workspace_ ? workspace_->threads() : ActionModel::maxThreads();
}

KnotWorkspace& KnotModel::workspace(KnotActionData& d) const {
  // A setup error, not a numerical one: the data's slot has no RK4 stages (or has them for
  // nothing), and a knot must not silently integrate otherwise than it was set up for.
  if (d.integrator_ != integrator_)
    throw std::logic_error(std::string("KnotModel: data made for the ") + toString(d.integrator_) +
                           " integrator, the knot integrates by " + toString(integrator_) +
                           " (setIntegrator after createData)");
  // The problem never runs more threads than the shared workspace serves (maxThreads).
  if (d.slot_ < 0) return *d.own_;
  return workspace_->scratch(d.slot_, omp_get_thread_num());
}

std::unique_ptr<ActionData> KnotModel::createData() const {
  const int slot = workspace_ ? workspace_->reserve(contacts_, costs_, integrator_) : -1;
  return std::make_unique<KnotActionData>(model_, contacts_, costs_, slot, integrator_);
}

KnotContext KnotModel::context(KnotActionData& d, KnotWorkspace& w) const {
  // An RK4 contact knot's forces are its stage 1's, λ at x: their Jacobians are in the Rk4Data.
  // (The kinematics are stage 1's in w.data with either integrator.)
  const bool rk4 = mode_ == KnotMode::Contact && integrator_ == Integrator::Rk4;
  const Eigen::MatrixXd& Gx = rk4 ? w.rk4->Gx : w.knot.Gx;
  const Eigen::MatrixXd& Gu = rk4 ? w.rk4->Gu : w.knot.Gu;
  return KnotContext{model_, w.data, &contacts_, &d.forces_, &Gx, &Gu};
}

// The dynamics of the knot's mode; false (with the status set, the state held and the cost
// infinite) when they cannot be solved.
bool KnotModel::dynamics(KnotActionData& d, KnotWorkspace& w,
                         const Eigen::Ref<const Eigen::VectorXd>& x,
                         const Eigen::Ref<const Eigen::VectorXd>& u, bool derivatives) const {
  const int nq = model_.nq, nv = model_.nv;
  const auto q = x.head(nq);
  const auto v = x.tail(nv);
  Data& data = w.data;
  KnotData& kd = w.knot;
  ContactData& cd = kd.contact;
  ContactStatus s;
  if (mode_ == KnotMode::Contact && integrator_ == Integrator::Rk4) {
    // calcDiff runs the four stages again rather than reusing calc's: a kept solve would have to
    // hold the four stages' kinematics and factors (stages 2-4 live in one shared Data), and the
    // solves are a smaller share of an RK4 calcDiff than of an Euler one (each stage's
    // derivatives follow its solve).
    d.solve_reused = false;
    Rk4Data& rd = *w.rk4;
    s = derivatives ? knotDynamicsRk4Derivatives(model_, data, contacts_, rd, q, v, u, dt_, damping)
                    : knotDynamicsRk4(model_, data, contacts_, rd, q, v, u, dt_, damping);
    if (s == ContactStatus::Ok) {
      d.x_next.head(nq) = rd.q_next;
      d.x_next.tail(nv) = rd.v_next;
      if (derivatives) {
        // Swapped as with Euler: knotDynamicsRk4Derivatives rewrites every entry of rd.Fx, rd.Fu.
        d.Fx.swap(rd.Fx);
        d.Fu.swap(rd.Fu);
        // Fx's velocity rows are not [dt a_q, I + dt a_v] here: the solvers must not take the
        // Euler-structured products (action.hpp, EulerStructure).
        d.euler.valid = false;
      }
    }
    d.forces_ = rd.contact.lambda;
    d.nc_ = rd.contact.nc;
  } else if (mode_ == KnotMode::Contact) {
    d.solve_reused = derivatives && keptSolveMatches(d, x, u);
    if (d.solve_reused) {
      // calc's solve at this point (x⁺ and λ are still in d): only the Jacobians. keepSolve
      // trades the buffers back afterwards.
      d.kept_.trade(data, cd);
      cd.lambda = d.forces_;
      kd.step = dt_ * d.x_next.tail(nv);
      knotDerivativesAtSolution(model_, data, contacts_, kd, v, dt_);
      s = ContactStatus::Ok;
    } else {
      s = derivatives ? knotDynamicsDerivatives(model_, data, contacts_, kd, q, v, u, dt_, damping)
                      : knotDynamics(model_, data, contacts_, kd, q, v, u, dt_, damping);
      if (s == ContactStatus::Ok) {
        d.x_next.head(nq) = kd.q_next;
        d.x_next.tail(nv) = kd.v_next;
      }
    }
    if (s == ContactStatus::Ok) {
      if (derivatives) {
        // Swapped, not copied: knotDynamicsDerivatives rewrites every entry of kd.Fx, kd.Fu on each
        // call, so the two buffers can trade places (O(1), no allocation; the workspace's pair then
        // serves the next knot).
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
      }
    }
    d.forces_ = cd.lambda;
  } else {
    d.solve_reused = false;
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
    d.forces_ = cd.impulses;
  }
  if (mode_ == KnotMode::Impulse || integrator_ == Integrator::Euler) d.nc_ = cd.nc;
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

bool KnotModel::keptSolveMatches(const KnotActionData& d,
                                 const Eigen::Ref<const Eigen::VectorXd>& x,
                                 const Eigen::Ref<const Eigen::VectorXd>& u) const {
  const KeptSolve& k = d.kept_;
  // Exact comparisons: the kept solve is reused only where it is bit for bit the one calcDiff
  // would compute.
  return k.valid && k.knot == this && k.contacts_version == contacts_.version() && k.dt == dt_ &&
         k.damping == damping && x.size() == k.x.size() && u.size() == k.u.size() && k.x == x &&
         k.u == u;
}

// After the knot's dynamics and costs: the workspace's solve goes to the knot (contact mode), for
// a calcDiff at the same point.
void KnotModel::keepSolve(KnotActionData& d, KnotWorkspace& w,
                          const Eigen::Ref<const Eigen::VectorXd>& x,
                          const Eigen::Ref<const Eigen::VectorXd>& u) const {
  KeptSolve& k = d.kept_;
  // Euler contact knots only: an RK4 calcDiff solves its four stages again (dynamics()).
  k.valid = mode_ == KnotMode::Contact && integrator_ == Integrator::Euler &&
            d.contact_status == ContactStatus::Ok;
  if (!k.valid) return;
  k.trade(w.data, w.knot.contact);
  k.knot = this;
  k.contacts_version = contacts_.version();
  k.dt = dt_;
  k.damping = damping;
  k.x = x;
  k.u = u;
}

void KnotModel::calc(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                     const Eigen::Ref<const Eigen::VectorXd>& u) const {
  auto& d = static_cast<KnotActionData&>(data);
  KnotWorkspace& w = workspace(d);
  const bool ok = dynamics(d, w, x, u, false);
  if (ok) {
    d.cost = costs_.calc(w.costs, context(d, w), x, u);
    if (!std::isfinite(d.cost)) {
      d.status = KnotStatus::NonFinite;
      d.cost = kInfinity;
    }
  }
  keepSolve(d, w, x, u);
}

void KnotModel::calcDiff(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                         const Eigen::Ref<const Eigen::VectorXd>& u) const {
  auto& d = static_cast<KnotActionData&>(data);
  KnotWorkspace& w = workspace(d);
  const bool ok = dynamics(d, w, x, u, true);
  if (ok) {
    d.cost = costs_.calcDiff(w.costs, context(d, w), x, u, d.Lx, d.Lu, d.Lxx, d.Lxu, d.Luu);
    if (!std::isfinite(d.cost) || !d.Lx.allFinite() || !d.Lu.allFinite()) {
      d.status = KnotStatus::NonFinite;
      d.cost = kInfinity;
    }
  }
  keepSolve(d, w, x, u);
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
