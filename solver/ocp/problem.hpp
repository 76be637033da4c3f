#pragma once
// A shooting problem: the initial state x0, T running knots and a terminal knot (paper §III).
// Knot k maps (x_k, u_k) to x_{k+1}; the solvers own the trajectories (xs, us) and ask the problem
// to evaluate all knots. calc / calcDiff of the knots are independent, so they run in parallel
// (OpenMP, thread count configurable); results do not depend on the thread count.
//
// The receding horizon rewrites the problem in place: shift(k) moves every knot (model and data)
// k places towards the start, the first k knots wrapping around to the end where the caller
// re-configures them (mode, contacts, references) for the new end of the horizon.

#include <vector>

#include "solver/ocp/action.hpp"

namespace stride {

class ShootingProblem {
 public:
  // Throws std::invalid_argument for an empty or null knot, a terminal knot that is not terminal,
  // knots on different state spaces, or an x0 of the wrong size.
  ShootingProblem(const Eigen::VectorXd& x0, std::vector<std::unique_ptr<ActionModel>> running,
                  std::unique_ptr<ActionModel> terminal);

  int horizon() const { return static_cast<int>(running_.size()); }  // T
  const StateSpace& state() const { return terminal_->state(); }
  int nx() const { return state().nx(); }
  int ndx() const { return state().ndx(); }
  int nu(int k) const { return running_[k]->nu(); }
  int maxNu() const { return max_nu_; }

  const Eigen::VectorXd& x0() const { return x0_; }
  // Copies x0 (no allocation); false when the size is wrong or a value is not finite.
  bool setX0(const Eigen::Ref<const Eigen::VectorXd>& x0);

  ActionModel& knot(int k) { return *running_[k]; }
  const ActionModel& knot(int k) const { return *running_[k]; }
  ActionData& data(int k) { return *running_data_[k]; }
  const ActionData& data(int k) const { return *running_data_[k]; }
  ActionModel& terminal() { return *terminal_; }
  const ActionModel& terminal() const { return *terminal_; }
  ActionData& terminalData() { return *terminal_data_; }
  const ActionData& terminalData() const { return *terminal_data_; }
  // A knot as its concrete type (for reconfiguration); nullptr when the type differs.
  template <typename M>
  M* knotAs(int k) {
    return dynamic_cast<M*>(running_[k].get());
  }

  // Evaluates every knot at (xs[k], us[k]) (xs has T + 1 entries, us T); returns the total cost
  // (+inf when a knot failed: see data(k).status).
  double calc(const std::vector<Eigen::VectorXd>& xs, const std::vector<Eigen::VectorXd>& us);
  // calc and the derivatives of knots begin .. end - 1, index T standing for the terminal knot
  // (every knot by default; Solver::computeDerivatives goes in chunks, to check its deadline
  // between them); returns the total cost over all knots, each at its last evaluation.
  double calcDiff(const std::vector<Eigen::VectorXd>& xs, const std::vector<Eigen::VectorXd>& us,
                  int begin = 0, int end = -1);

  // Moves knot k + n to k for all k (models with their data); the first n knots become the last n.
  void shift(int n);

  // Threads for calc / calcDiff. Knots that share per-thread scratch (knot.hpp) bound it: the
  // problem runs on at most the smallest ActionModel::maxThreads() of its knots.
  void setThreads(int threads) { threads_ = threads < 1 ? 1 : threads; }
  int threads() const { return threads_; }

 private:
  double evaluate(const std::vector<Eigen::VectorXd>& xs, const std::vector<Eigen::VectorXd>& us,
                  bool derivatives, int begin, int end);

  Eigen::VectorXd x0_;
  Eigen::VectorXd empty_;  // the terminal knot's control
  std::vector<std::unique_ptr<ActionModel>> running_;
  std::vector<std::unique_ptr<ActionData>> running_data_;
  std::unique_ptr<ActionModel> terminal_;
  std::unique_ptr<ActionData> terminal_data_;
  int max_nu_ = 0;
  int threads_ = 1;
  int max_threads_ = 1;  // the smallest maxThreads() of the knots
};

}  // namespace stride
