#pragma once
// The knot interface the solvers see (paper §III): a discrete dynamics x⁺ = f(x, u) with its
// Jacobians Fx, Fu, and a cost ℓ(x, u) with its gradient and (Gauss-Newton) Hessian, all in the
// tangent space of the state. calc computes values, calcDiff values and derivatives; both write
// into an ActionData built once by the model. New kinds of knots need no solver change.

#include <limits>
#include <memory>

#include "solver/multibody/model.hpp"

namespace stride {

// The state manifold: x = [q; v] of a robot (dx = [dq; dv], 2nv), or a vector space R^n.
class StateSpace {
 public:
  explicit StateSpace(const Model& model);
  explicit StateSpace(int n);

  int nx() const { return nx_; }
  int ndx() const { return ndx_; }
  const Model* model() const { return model_; }

  // x ⊕ dx.
  void integrate(const Eigen::Ref<const Eigen::VectorXd>& x,
                 const Eigen::Ref<const Eigen::VectorXd>& dx,
                 Eigen::Ref<Eigen::VectorXd> out) const;
  // x1 ⊖ x0: the dx with x0 ⊕ dx = x1.
  void difference(const Eigen::Ref<const Eigen::VectorXd>& x0,
                  const Eigen::Ref<const Eigen::VectorXd>& x1,
                  Eigen::Ref<Eigen::VectorXd> out) const;
  // The neutral state (neutral configuration, zero velocity; zero for R^n).
  Eigen::VectorXd zero() const;

 private:
  const Model* model_ = nullptr;
  int nx_, ndx_;
};

enum class KnotStatus : std::uint8_t {
  Ok,
  NonFinite,        // a non-finite input or result
  DynamicsFailure,  // the contact dynamics could not be solved (singular KKT system)
};
const char* toString(KnotStatus status);

// The structure of a semi-implicit Euler knot's Jacobians (ARCHITECTURE §3), which the Riccati
// recursion exploits to halve its products. With a = v̇(x, u), v⁺ = v + dt a, q⁺ = q ⊕ dt v⁺, the
// velocity rows of the Jacobians are G = ∂v⁺/∂x = [dt a_q, I + dt a_v] and H = ∂v⁺/∂u = dt a_u,
// and the configuration rows follow from them:
//   Fx = [Jq 0; 0 0] + [dt Jv; I] G,   Fu = [dt Jv; I] H,
// where Jq, Jv (the Jacobians of ⊕ at (q, dt v⁺)) are the identity except a leading nb x nb block
// (a free-flyer's 6 x 6). G and H are the bottom nv rows of Fx and Fu themselves, so the structure
// needs only these blocks: it refers to nothing outside the ActionData (a knot's scratch is
// shared with other knots and is gone after its calcDiff).
struct EulerStructure {
  bool valid = false;
  double dt = 0.0;
  int nb = 0;
  Eigen::Matrix<double, 6, 6> Jq, Jv;  // leading blocks, top-left nb x nb used
};

struct ActionData {
  ActionData(int nx, int ndx, int nu);
  virtual ~ActionData() = default;
  KnotStatus status = KnotStatus::Ok;
  double cost = 0.0;       // ℓ(x, u); +inf when status is not Ok
  Eigen::VectorXd x_next;  // f(x, u) (terminal knots: unused)
  Eigen::MatrixXd Fx, Fu;  // ndx x ndx, ndx x nu
  Eigen::VectorXd Lx, Lu;  // ndx, nu
  Eigen::MatrixXd Lxx, Lxu, Luu;
  EulerStructure euler;  // set by knots whose Fx, Fu have that structure (after calcDiff)
};

class ActionModel {
 public:
  ActionModel(const StateSpace& state, int nu) : state_(state), nu_(nu) {}
  virtual ~ActionModel() = default;
  ActionModel(const ActionModel&) = delete;
  ActionModel& operator=(const ActionModel&) = delete;

  const StateSpace& state() const { return state_; }
  int nu() const { return nu_; }

  virtual std::unique_ptr<ActionData> createData() const = 0;
  // f(x, u) and ℓ(x, u). Never throws for non-finite numbers: data.status says what went wrong.
  virtual void calc(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                    const Eigen::Ref<const Eigen::VectorXd>& u) const = 0;
  // calc and all derivatives.
  virtual void calcDiff(ActionData& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                        const Eigen::Ref<const Eigen::VectorXd>& u) const = 0;
  // Terminal knots have no dynamics; the solvers call them with u of size 0.
  virtual bool isTerminal() const { return false; }
  // How many threads may evaluate knots of this model at once (knots whose scratch is shared per
  // thread: knot.hpp); the problem runs on no more.
  virtual int maxThreads() const { return std::numeric_limits<int>::max(); }

 private:
  StateSpace state_;
  int nu_;
};

}  // namespace stride
