// After createData, no residual's calc / calcDiff and no CostModel::calc / calcDiff touches the
// heap, nor do the reference setters. As in tests/multibody/test_no_alloc.cpp, malloc and its
// relatives are interposed and counted (operator new and Eigen both end there), with Eigen's own
// check (EIGEN_RUNTIME_NO_MALLOC) armed as well; the interposition is per binary, hence this
// separate executable.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <random>

#include "ocp/residual_cases.hpp"
#include "solver/ocp/cost.hpp"

namespace stride {
namespace test_ocp_no_alloc {

using test_support::AllocationCounter;
using test_support::allocations;

using ocp_test::Knot;
using ocp_test::makeTerms;
using ocp_test::randomState;
using ocp_test::randomUniform;
using ocp_test::RobotSetup;
using ocp_test::robotSetups;
using ocp_test::Term;

TEST(OcpNoAllocation, CounterSeesAllocations) {
  AllocationCounter counter;
  Eigen::internal::set_is_malloc_allowed(true);
  // The pointers are volatile: clang may otherwise drop an allocation whose memory is not used,
  // with its free (gcc keeps them).
  double* volatile p = static_cast<double*>(std::malloc(64));
  std::free(p);
  std::vector<int> v(10);
  int* volatile data = v.data();
  (void)data;
  EXPECT_GE(counter.stop(), 2);
}

// Every residual alone, then all of them in one cost, with all contacts on and with one off.
TEST(OcpNoAllocation, ResidualsAndCost) {
  std::mt19937 rng(5);
  for (RobotSetup& s : robotSetups()) {
    const Model& m = s.model;
    const Eigen::VectorXd x = randomState(m, rng);
    Knot knot(m, s.contacts);
    const int nu = knot.kd.nu, ndx = 2 * m.nv;
    const Eigen::VectorXd u = randomUniform(rng, nu, 5.0);

    std::vector<Term> terms = makeTerms(s, nu, x, rng);
    std::vector<std::unique_ptr<ResidualData>> datas;
    for (const Term& t : terms) datas.push_back(t.residual->createData());
    CostModel cost(m.nv, nu);
    for (Term& t : makeTerms(s, nu, x, rng))
      cost.add(t.name, std::move(t.residual), std::move(t.activation));
    CostData cd = cost.createData();
    Eigen::VectorXd Lx(ndx), Lu(nu);
    Eigen::MatrixXd Lxx(ndx, ndx), Lxu(ndx, nu), Luu(nu, nu);

    // New references, set in place.
    const Eigen::VectorXd x_ref = randomState(m, rng), u_ref = randomUniform(rng, nu, 1.0);
    const Eigen::VectorXd f_ref = randomUniform(rng, s.contacts[0].dim, 1.0);
    StateResidual* state = cost.residual<StateResidual>("state");
    ControlResidual* control = cost.residual<ControlResidual>("control");
    FramePlacementResidual* placement = cost.residual<FramePlacementResidual>("placement");
    ContactForceResidual* force =
        cost.residual<ContactForceResidual>("force_" + s.contacts[0].name);
    FrictionConeResidual* cone = cost.residual<FrictionConeResidual>("cone_" + s.contacts[0].name);
    ASSERT_TRUE(state && control && placement && force && cone);

    auto run = [&](const KnotContext& ctx) {
      for (size_t i = 0; i < terms.size(); ++i) {
        terms[i].residual->calc(*datas[i], ctx, x, u);
        terms[i].residual->calcDiff(*datas[i], ctx, x, u);
      }
      state->setReference(x_ref);
      control->setReference(u_ref);
      placement->setReference(SE3(exp3(Eigen::Vector3d(0.1, 0.2, 0.3)), Eigen::Vector3d(1, 2, 3)));
      force->setReference(f_ref);
      cone->setFriction(0.5);
      cone->setSurfaceRotation(Eigen::Matrix3d::Identity());
      cone->setMinimumNormalForce(1.0);
      cost.calc(cd, ctx, x, u);
      cost.calcDiff(cd, ctx, x, u, Lx, Lu, Lxx, Lxu, Luu);
    };
    for (bool first_on : {true, false}) {
      s.contacts.setActive(0, first_on);
      const KnotContext ctx = knot.at(x, u);
      ASSERT_EQ(knot.status, ContactStatus::Ok);
      run(ctx);  // warm-up outside the counter
      long count;
      {
        AllocationCounter counter;
        run(ctx);
        count = counter.stop();
      }
      EXPECT_EQ(count, 0) << s.name << (first_on ? "" : ", first contact off");
    }
  }
}

}  // namespace test_ocp_no_alloc
}  // namespace stride
