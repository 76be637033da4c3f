#pragma once
// A linear-quadratic knot for the solver tests: x⁺ = A x + B u + c,
// ℓ = ½ xᵀQx + qᵀx + ½ uᵀRu + rᵀu + xᵀNu (terminal: ½ xᵀQx + qᵀx). The second implementation of
// the ActionModel interface, on a vector space.

#include <random>

#include "solver/ocp/action.hpp"

namespace stride::test_support {

struct LqKnot : ActionModel {
  LqKnot(int nx, int nu, bool terminal) : ActionModel(StateSpace(nx), nu), terminal(terminal) {}
  Eigen::MatrixXd A, B, Q, R, N;
  Eigen::VectorXd c, q, r;
  bool terminal;

  static std::unique_ptr<LqKnot> random(int nx, int nu, bool terminal, std::mt19937& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    auto rnd = [&](int r, int c) {
      Eigen::MatrixXd M(r, c);
      for (int i = 0; i < r; ++i)
        for (int j = 0; j < c; ++j) M(i, j) = n(rng);
      return M;
    };
    auto m = std::make_unique<LqKnot>(nx, terminal ? 0 : nu, terminal);
    const int u = m->nu();
    m->A = Eigen::MatrixXd::Identity(nx, nx) + 0.1 * rnd(nx, nx);
    m->B = 0.5 * rnd(nx, u);
    m->c = 0.1 * rnd(nx, 1);
    const Eigen::MatrixXd Lq = rnd(nx, nx), Lr = rnd(u, u);
    m->Q = Lq * Lq.transpose() / nx + 0.1 * Eigen::MatrixXd::Identity(nx, nx);
    m->R = Lr * Lr.transpose() / std::max(u, 1) + 0.5 * Eigen::MatrixXd::Identity(u, u);
    m->N = 0.05 * rnd(nx, u);
    m->q = rnd(nx, 1);
    m->r = rnd(u, 1);
    return m;
  }

  bool isTerminal() const override { return terminal; }
  std::unique_ptr<ActionData> createData() const override {
    return std::make_unique<ActionData>(state().nx(), state().ndx(), nu());
  }
  void calc(ActionData& d, const Eigen::Ref<const Eigen::VectorXd>& x,
            const Eigen::Ref<const Eigen::VectorXd>& u) const override {
    d.cost = 0.5 * x.dot(Q * x) + q.dot(x);
    if (!terminal) {
      d.cost += 0.5 * u.dot(R * u) + r.dot(u) + x.dot(N * u);
      d.x_next = A * x + B * u + c;
    }
    d.status = KnotStatus::Ok;
  }
  void calcDiff(ActionData& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& u) const override {
    calc(d, x, u);
    d.Lx = Q * x + q;
    d.Lxx = Q;
    if (!terminal) {
      d.Lx += N * u;
      d.Lu = R * u + r + N.transpose() * x;
      d.Luu = R;
      d.Lxu = N;
      d.Fx = A;
      d.Fu = B;
    }
  }
};

}  // namespace stride::test_support
