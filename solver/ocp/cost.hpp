#pragma once
// A knot's cost: a named sum of terms, each weight · activation(residual). Terms are added at
// setup; weights, references and on/off switches change in place every tick (no allocation).

#include <string>
#include <vector>

#include "solver/ocp/activation.hpp"
#include "solver/ocp/residual.hpp"

namespace stride {

struct CostTerm {
  std::string name;
  std::unique_ptr<Residual> residual;
  Activation activation;
  double weight = 1.0;
  bool active = true;
};

struct CostData {
  std::vector<std::unique_ptr<ResidualData>> residuals;  // one per term
  Eigen::VectorXd g, h;                                  // weighted activation derivatives
  Eigen::MatrixXd HRx, HRu;                              // Gauss-Newton product workspaces
  double value = 0.0;
};

class CostModel {
 public:
  CostModel(int nv, int nu) : nv_(nv), nu_(nu) {}
  CostModel(const CostModel&) = delete;
  CostModel& operator=(const CostModel&) = delete;

  // Adds a term (setup only). Throws std::invalid_argument for a duplicate name, a residual of
  // another state or control size, or an activation of another dimension. Returns its index.
  int add(const std::string& name, std::unique_ptr<Residual> residual, Activation activation,
          double weight = 1.0);
  int find(const std::string& name) const;  // -1 when absent
  int size() const { return static_cast<int>(terms_.size()); }
  CostTerm& operator[](int term) { return terms_[term]; }
  const CostTerm& operator[](int term) const { return terms_[term]; }
  // The residual of a term as its concrete type, to rewrite its reference (nullptr when the name
  // is absent or the type differs). Look it up once at setup, keep the pointer.
  template <typename R>
  R* residual(const std::string& name) {
    const int i = find(name);
    return i < 0 ? nullptr : dynamic_cast<R*>(terms_[i].residual.get());
  }

  int nv() const { return nv_; }
  int nu() const { return nu_; }
  int maxDim() const;

  CostData createData() const;
  // Σ weight · a(r) over the active terms.
  double calc(CostData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
              const Eigen::Ref<const Eigen::VectorXd>& u) const;
  // The value (returned) and its gradient and Gauss-Newton Hessian, written (not added) into
  // Lx, Lu, Lxx, Lxu, Luu.
  double calcDiff(CostData& d, const KnotContext& ctx, const Eigen::Ref<const Eigen::VectorXd>& x,
                  const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> Lx,
                  Eigen::Ref<Eigen::VectorXd> Lu, Eigen::Ref<Eigen::MatrixXd> Lxx,
                  Eigen::Ref<Eigen::MatrixXd> Lxu, Eigen::Ref<Eigen::MatrixXd> Luu) const;

 private:
  int nv_, nu_;
  std::vector<CostTerm> terms_;
};

}  // namespace stride
