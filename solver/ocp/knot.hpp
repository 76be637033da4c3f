#pragma once
// The robot's knots (paper §IV-V):
//   - a contact knot: KKT contact dynamics with the active contacts, then semi-implicit Euler
//     (eq. 11); its cost may depend on the contact forces λ = g(x, u), whose Jacobians Gx, Gu
//     give the Gauss-Newton terms of eq. 12;
//   - an impulse knot: the touch-down of new contacts, x⁺ = (q, v⁺) with the impulse Λ as its
//     forces; u has no effect there (Fu = 0);
//   - a terminal knot: a cost on the final state.
// Contact and impulse are two modes of one knot, switched in place: the receding horizon moves a
// touch-down from one knot to the previous one every tick, so a knot must change mode without
// being rebuilt.

#include "solver/contact/knot_dynamics.hpp"
#include "solver/ocp/action.hpp"
#include "solver/ocp/cost.hpp"

namespace stride {

enum class KnotMode : std::uint8_t { Contact, Impulse };

// Multibody workspaces (Data) shared by the knots of a problem, one per thread. A knot's Data is
// scratch within one calc / calcDiff (the knot keeps its results in its own KnotActionData), so the
// knots a thread evaluates one after the other can reuse one Data that stays in cache, instead of
// each streaming its own from memory: measured on solo, 13 against 24 µs per knot calcDiff over
// 100 knots. Threads beyond the pool's size fall back to the knot's own Data.
class SharedWorkspace {
 public:
  SharedWorkspace(const Model& model, int threads);
  int threads() const { return static_cast<int>(data_.size()); }
  Data& forThread(int thread) { return *data_[thread]; }

 private:
  std::vector<std::unique_ptr<Data>> data_;
};

struct KnotActionData : ActionData {
  KnotActionData(const Model& model, const ContactSet& contacts, const CostModel& costs);
  Data data;  // multibody workspace of this knot when it has no shared one
  KnotData knot;
  CostData costs;
  ContactStatus contact_status = ContactStatus::Ok;
  Eigen::VectorXd v;  // scratch
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
  ContactSet& contacts() { return contacts_; }
  const ContactSet& contacts() const { return contacts_; }
  CostModel& costs() { return costs_; }
  const CostModel& costs() const { return costs_; }
  const Model& model() const { return model_; }
  // The paper's damped Cholesky for rank-deficient contact sets (0: none).
  double damping = 0.0;
  // Impulse knots: coefficient of restitution (0: perfectly inelastic touch-down).
  double restitution = 0.0;

  std::unique_ptr<ActionData> createData() const override;
  void calc(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override;
  void calcDiff(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override;

 private:
  bool dynamics(KnotActionData& d, Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u, bool derivatives) const;
  KnotContext context(KnotActionData& d, Data& data) const;
  Data& workspace(KnotActionData& d) const;

  const Model& model_;
  ContactSet contacts_;
  CostModel costs_;
  double dt_;
  KnotMode mode_ = KnotMode::Contact;
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
