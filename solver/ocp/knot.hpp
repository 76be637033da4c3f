#pragma once
// The robot's knots (paper §IV-V):
//   - a contact knot: KKT contact dynamics with the active contacts, then semi-implicit Euler
//     (eq. 11); its cost may depend on the contact forces λ = g(x, u), whose Jacobians Gx, Gu
//     give the Gauss-Newton terms of eq. 12;
//   - an impulse knot: the touch-down of new contacts, x⁺ = (q, v⁺) with the impulse Λ as its
//     forces; u has no effect there (Fu = 0);
//   - a terminal knot: a cost on the final state.
// A contact knot integrates by semi-implicit Euler (knot_dynamics.hpp) or, chosen per knot at
// setup (setIntegrator), by Runge-Kutta-Munthe-Kaas 4 (knot_rk4.hpp). An impulse is
// instantaneous: it has nothing to integrate, and is the same under both.
// Contact and impulse are two modes of one knot, switched in place: the receding horizon moves a
// touch-down from one knot to the previous one every tick, so a knot must change mode without
// being rebuilt.

#include <string>
#include <typeinfo>

#include "solver/contact/knot_dynamics.hpp"
#include "solver/contact/knot_rk4.hpp"
#include "solver/ocp/action.hpp"
#include "solver/ocp/cost.hpp"

namespace stride {

enum class KnotMode : std::uint8_t { Contact, Impulse };

// How a contact knot integrates its dynamics over dt. Euler: one KKT solve per knot, first order,
// and the structure of Fx the solvers exploit (action.hpp, EulerStructure). Rk4: four solves per
// knot, fourth order (a free-floating body's momentum is conserved to O(dt⁴) per knot, not
// O(dt)), Fx without that structure.
enum class Integrator : std::uint8_t { Euler, Rk4 };
const char* toString(Integrator integrator);  // "euler", "rk4"
// "euler" or "rk4" (exactly, lower case); false for anything else, out untouched.
bool parseIntegrator(const std::string& name, Integrator& out);

// The scratch of one knot's calc / calcDiff: the multibody workspace, the contact dynamics
// workspaces (KKT factors, ∂v̇, ∂λ, Gx, Gu, the Euler step's Jacobians) and the cost's residual
// workspaces. None of it is read after the call: what later stages need (x⁺, Fx, Fu, the cost
// derivatives, λ) is copied into the knot's KnotActionData.
struct KnotWorkspace {
  KnotWorkspace(const Model& model, const ContactSet& contacts, const CostModel& costs,
                Integrator integrator = Integrator::Euler);
  Data data;
  KnotData knot;  // the Euler step, and the impulse of either integrator
  CostData costs;
  // Rk4 only (null for Euler: stages 2-4 need a second Data, ~100 KB on a humanoid): the RK4
  // stages. Stage 1 runs in `data` and rk4->contact, so the costs read the kinematics and λ at x.
  std::unique_ptr<Rk4Data> rk4;
};

// Knot workspaces shared by the knots of a problem, one per thread. Every byte a knot touches in
// calc / calcDiff that it does not keep is scratch, so the knots a thread evaluates one after the
// other reuse one workspace that stays in cache instead of each streaming its own from memory
// (solo, 100 knots: 24 µs per knot calcDiff with a workspace per knot, 18 with only the Data
// shared, 12 with the whole scratch shared: the same as in a 4-knot problem; see README.md).
//
// A workspace serves knots of the same model whose contact sets have the same size and whose
// costs have the same terms (residual types and dimensions, in order): residual workspaces depend
// on nothing else (residual.hpp). Knots that differ get a workspace of their own kind (a "slot"),
// created at setup by KnotModel::createData.
class SharedWorkspace {
 public:
  SharedWorkspace(const Model& model, int threads);
  int threads() const { return threads_; }
  // The multibody workspace of a thread (shared by all slots).
  Data& forThread(int thread) { return *data_[thread]; }
  // Setup: the slot serving a knot with these contacts, costs and integrator, created when none
  // fits (an Rk4 knot needs a workspace with the RK4 stages).
  int reserve(const ContactSet& contacts, const CostModel& costs,
              Integrator integrator = Integrator::Euler);
  KnotWorkspace& scratch(int slot, int thread) { return *slots_[slot].scratch[thread]; }

 private:
  struct Slot {
    int max_nc;
    Integrator integrator;
    std::vector<std::pair<const std::type_info*, int>> terms;  // residual type and dimension
    std::vector<std::unique_ptr<KnotWorkspace>> scratch;       // one per thread
  };
  const Model& model_;
  int threads_;
  std::vector<std::unique_ptr<Data>> data_;
  std::vector<Slot> slots_;
};

// The contact solve of a knot's last calc (or calcDiff), kept so that its calcDiff at the same
// point computes only the Jacobians: in a DDP iteration calcDiff runs at the point of the
// accepted rollout, whose calc has just solved the KKT system there (solo: the solve is a
// quarter of calcDiff). It holds the buffers contactDynamicsDerivativesAtSolution and the costs
// read (kinematics, the factors of M and of the Schur complement, the constraint rows, v̇),
// traded with the workspace's by swapping (O(1), no copy): after calc the knot keeps the
// workspace's fresh buffers and the workspace gets the knot's old ones, which the next knot
// overwrites. Valid only for the same knot model, x, u, dt, damping and contact set version.
struct KeptSolve {
  KeptSolve(const Model& model, const ContactSet& contacts);
  // Swaps the buffers with the workspace's (its own inverse).
  void trade(Data& data, ContactData& cd);

  bool valid = false;
  const void* knot = nullptr;
  std::uint64_t contacts_version = 0;
  double dt = 0.0, damping = 0.0;
  Eigen::VectorXd x, u;
  int nc = 0;
  std::vector<SE3> oMi;
  Matrix6Xd J;
  std::vector<Inertia> oYbody;
  std::vector<Vector6d> v, a;
  Eigen::MatrixXd Ltdl, Jc, Yt, K;
  Eigen::VectorXd ddq;
};

// What a knot keeps between calls: the ActionData results, the contact forces, the status of
// the contact solve and the solve itself (KeptSolve). (The scratch lives in a KnotWorkspace: the
// problem's shared one, or `own` for a knot built without one.)
struct KnotActionData : ActionData {
  KnotActionData(const Model& model, const ContactSet& contacts, const CostModel& costs, int slot,
                 Integrator integrator = Integrator::Euler);
  // The contact forces of the last calc / calcDiff, each contact's in its force frame, the active
  // contacts stacked in the set's order (top nc() entries): λ in contact mode, the impulses Λ in
  // impulse mode.
  const Eigen::VectorXd& forces() const { return forces_; }
  int nc() const { return nc_; }
  ContactStatus contact_status = ContactStatus::Ok;
  // Whether the last calcDiff took the contact solve kept from calc (KeptSolve) instead of
  // solving again (never with Rk4: its calcDiff runs the four stages again, see knot.cpp).
  bool solve_reused = false;
  // The integrator the data (and its workspace slot) was made for.
  Integrator integrator() const { return integrator_; }

 private:
  friend class KnotModel;
  Eigen::VectorXd forces_;  // maxNc
  int nc_ = 0;
  KeptSolve kept_;
  int slot_;  // of the shared workspace, -1 without one
  Integrator integrator_;
  std::unique_ptr<KnotWorkspace> own_;  // without a shared workspace only
};

class KnotModel : public ActionModel {
 public:
  // contacts: every contact the knot may use (copied; switch them per phase with contacts()).
  // workspace: shared by the knots of one problem (recommended), or null for the knot's own.
  KnotModel(const Model& model, const ContactSet& contacts, double dt,
            std::shared_ptr<SharedWorkspace> workspace = nullptr);

  KnotMode mode() const { return mode_; }
  void setMode(KnotMode mode) { mode_ = mode; }
  double dt() const { return dt_; }
  void setDt(double dt) { dt_ = dt; }
  // Setup only, before createData: the data and its workspace slot are made for the integrator
  // (calc / calcDiff on data made for another one throw std::logic_error).
  Integrator integrator() const { return integrator_; }
  void setIntegrator(Integrator integrator) { integrator_ = integrator; }
  ContactSet& contacts() { return contacts_; }
  const ContactSet& contacts() const { return contacts_; }
  CostModel& costs() { return costs_; }
  const CostModel& costs() const { return costs_; }
  const Model& model() const { return model_; }
  // The paper's damped Cholesky for rank-deficient contact sets (0: none).
  double damping = 0.0;
  // Impulse knots: coefficient of restitution (0: perfectly inelastic touch-down).
  double restitution = 0.0;

  // Also reserves the knot's slot in the shared workspace: call it after the costs are set up.
  std::unique_ptr<ActionData> createData() const override;
  void calc(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  // The shared workspace's thread count (unlimited without one).
  int maxThreads() const override;

 private:
  bool dynamics(KnotActionData& d, KnotWorkspace& w, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u, bool derivatives) const;
  KnotContext context(KnotActionData& d, KnotWorkspace& w) const;
  KnotWorkspace& workspace(KnotActionData& d) const;
  bool keptSolveMatches(const KnotActionData& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                        const Eigen::Ref<const Eigen::VectorXd>& u) const;
  void keepSolve(KnotActionData& d, KnotWorkspace& w, const Eigen::Ref<const Eigen::VectorXd>& x,
                 const Eigen::Ref<const Eigen::VectorXd>& u) const;

  const Model& model_;
  ContactSet contacts_;
  CostModel costs_;
  double dt_;
  KnotMode mode_ = KnotMode::Contact;
  Integrator integrator_ = Integrator::Euler;
  std::shared_ptr<SharedWorkspace> workspace_;
};

struct TerminalActionData : ActionData {
  TerminalActionData(const Model& model, const CostModel& costs);
  Data data;
  CostData costs;
};

class TerminalModel : public ActionModel {
 public:
  explicit TerminalModel(const Model& model);
  CostModel& costs() { return costs_; }
  const CostModel& costs() const { return costs_; }

  std::unique_ptr<ActionData> createData() const override;
  // u is ignored (size 0).
  void calc(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  bool isTerminal() const override { return true; }

 private:
  const Model& model_;
  CostModel costs_;
};

}  // namespace stride
