#include "solver/ocp/problem.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stride {

ShootingProblem::ShootingProblem(const Eigen::VectorXd& x0,
                                 std::vector<std::unique_ptr<ActionModel>> running,
                                 std::unique_ptr<ActionModel> terminal)
    : x0_(x0), running_(std::move(running)), terminal_(std::move(terminal)) {
  if (!terminal_) throw std::invalid_argument("ShootingProblem: null terminal knot");
  if (!terminal_->isTerminal())
    throw std::invalid_argument("ShootingProblem: the terminal knot is not a terminal model");
  if (running_.empty()) throw std::invalid_argument("ShootingProblem: no running knots");
  const StateSpace& s = terminal_->state();
  if (x0_.size() != s.nx())
    throw std::invalid_argument("ShootingProblem: x0 has size " + std::to_string(x0_.size()) +
                                ", the state " + std::to_string(s.nx()));
  for (size_t k = 0; k < running_.size(); ++k) {
    const ActionModel* m = running_[k].get();
    if (!m) throw std::invalid_argument("ShootingProblem: null knot " + std::to_string(k));
    if (m->isTerminal())
      throw std::invalid_argument("ShootingProblem: knot " + std::to_string(k) + " is terminal");
    if (m->state().nx() != s.nx() || m->state().ndx() != s.ndx() || m->state().model() != s.model())
      throw std::invalid_argument("ShootingProblem: knot " + std::to_string(k) +
                                  " lives on another state space");
    max_nu_ = std::max(max_nu_, m->nu());
    running_data_.push_back(m->createData());
  }
  terminal_data_ = terminal_->createData();
  max_threads_ = terminal_->maxThreads();
  for (const auto& m : running_) max_threads_ = std::min(max_threads_, m->maxThreads());
}

bool ShootingProblem::setX0(const Eigen::Ref<const Eigen::VectorXd>& x0) {
  if (x0.size() != x0_.size() || !x0.allFinite()) return false;
  x0_ = x0;
  return true;
}

namespace {
template <typename F>
void forEachKnot(int n, int threads, F&& f) {
  if (threads <= 1) {
    for (int k = 0; k < n; ++k) f(k);
    return;
  }
  // Static schedule: knots cost about the same, and no scheduler state is allocated per call.
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int k = 0; k < n; ++k) f(k);
}
}  // namespace

double ShootingProblem::calc(const std::vector<Eigen::VectorXd>& xs,
                             const std::vector<Eigen::VectorXd>& us) {
  return evaluate(xs, us, false, 0, horizon() + 1);
}

double ShootingProblem::calcDiff(const std::vector<Eigen::VectorXd>& xs,
                                 const std::vector<Eigen::VectorXd>& us, int begin, int end) {
  const int last = horizon() + 1;
  end = end < 0 ? last : std::min(end, last);
  return evaluate(xs, us, true, std::max(begin, 0), end);
}

double ShootingProblem::evaluate(const std::vector<Eigen::VectorXd>& xs,
                                 const std::vector<Eigen::VectorXd>& us, bool derivatives,
                                 int begin, int end) {
  const int T = horizon();
  // Knot indices begin .. end - 1, T being the terminal knot.
  forEachKnot(end - begin, std::min(threads_, max_threads_), [&](int i) {
    const int k = begin + i;
    ActionModel& m = k < T ? *running_[k] : *terminal_;
    ActionData& d = k < T ? *running_data_[k] : *terminal_data_;
    const Eigen::VectorXd& u = k < T ? us[k] : empty_;
    if (derivatives)
      m.calcDiff(d, xs[k], u);
    else
      m.calc(d, xs[k], u);
  });
  // Summed in knot order, after the parallel part: the same total for any thread count.
  double cost = terminal_data_->cost;
  for (int k = 0; k < T; ++k) cost += running_data_[k]->cost;
  return cost;
}

void ShootingProblem::shift(int n) {
  const int T = horizon();
  n = ((n % T) + T) % T;
  if (n == 0) return;
  std::rotate(running_.begin(), running_.begin() + n, running_.end());
  std::rotate(running_data_.begin(), running_data_.begin() + n, running_data_.end());
}

}  // namespace stride
