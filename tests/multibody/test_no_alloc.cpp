// After Data is built, no multibody algorithm touches the heap. Every allocation in the process is
// counted by interposing malloc and its relatives (operator new and Eigen both end there), and
// Eigen's own check (EIGEN_RUNTIME_NO_MALLOC) is armed around the calls as well.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <random>

#include "config/robot_config.hpp"
#include "solver/contact/knot_dynamics.hpp"
#include "solver/multibody/aba.hpp"
#include "solver/multibody/aba_derivatives.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/rnea_derivatives.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace test_no_alloc {

using test_support::AllocationCounter;
using test_support::allocations;

void runAllAlgorithms(const Model& model, Data& data, const Eigen::VectorXd& q,
                      const Eigen::VectorXd& v, const Eigen::VectorXd& a, Matrix6Xd& J,
                      Eigen::VectorXd& qnext, Eigen::VectorXd& dq, Eigen::MatrixXd& Jint) {
  forwardKinematics(model, data, q);
  forwardKinematics(model, data, q, v);
  forwardKinematics(model, data, q, v, a);
  updateFramePlacements(model, data);
  const int frame = model.nframes() - 1;
  getFrameVelocity(model, data, frame, ReferenceFrame::Local);
  getFrameAcceleration(model, data, frame, ReferenceFrame::LocalWorldAligned);
  getFrameClassicalAcceleration(model, data, frame, ReferenceFrame::LocalWorldAligned);
  computeJointJacobians(model, data, q);
  getFrameJacobian(model, data, frame, ReferenceFrame::Local, J);
  getFrameJacobian(model, data, frame, ReferenceFrame::LocalWorldAligned, J);
  getJointJacobian(model, data, model.njoints() - 1, ReferenceFrame::World, J);
  rnea(model, data, q, v, a);
  nonLinearEffects(model, data, q, v);
  computeGeneralizedGravity(model, data, q);
  crba(model, data, q);
  aba(model, data, q, v, a);
  centerOfMass(model, data, q);
  centerOfMass(model, data, q, v);
  jacobianCenterOfMass(model, data, q);
  computeCentroidalMomentum(model, data, q, v);
  computeCentroidalMap(model, data, q);
  integrate(model, q, v, qnext);
  difference(model, q, qnext, dq);
  dIntegrate(model, q, v, Jint, ArgumentPosition::Second);
  dDifference(model, q, qnext, Jint, ArgumentPosition::First);
}

void expectNoAllocation(const Model& model) {
  Data data(model);
  std::mt19937 rng(7);
  const Eigen::VectorXd q = randomConfiguration(model, rng);
  const Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv);
  const Eigen::VectorXd a = Eigen::VectorXd::Random(model.nv);
  Matrix6Xd J(6, model.nv);
  Eigen::VectorXd qnext(model.nq), dq(model.nv);
  Eigen::MatrixXd Jint(model.nv, model.nv);
  runAllAlgorithms(model, data, q, v, a, J, qnext, dq, Jint);  // warm-up outside the counter
  long count;
  {
    AllocationCounter counter;
    runAllAlgorithms(model, data, q, v, a, J, qnext, dq, Jint);
    count = counter.stop();
  }
  EXPECT_EQ(count, 0) << model.name << ": heap allocations inside the algorithms";
}

TEST(NoAllocation, CounterSeesAllocations) {
  // The counter must be able to fail: an Eigen heap vector and a std::vector are both seen.
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

TEST(NoAllocation, SharedRobots) {
  expectNoAllocation(buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/talos/talos_reduced.urdf",
                                        RootJoint::FreeFlyer));
  expectNoAllocation(
      buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/ur5/ur5_robot.urdf", RootJoint::Fixed));
}

TEST(NoAllocation, InHouseRobots) {
  expectNoAllocation(loadRobot(STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml").model);
  expectNoAllocation(
      loadRobot(STRIDE_CONFIG_DIR "/robots/stride_humanoid/stride_humanoid.yaml").model);
}

// Derivatives, contact and impulse dynamics and the knot: nothing allocates after setup, for any
// active subset of the contact set.
TEST(NoAllocation, DerivativesContactsAndKnots) {
  struct Setup {
    Model model;
    std::vector<std::pair<std::string, int>> contacts;
  } setups[] = {
      {buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/solo12/solo12.urdf", RootJoint::FreeFlyer),
       {{"FL_FOOT", 3}, {"FR_FOOT", 3}, {"HL_FOOT", 3}, {"HR_FOOT", 3}}},
      {buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/talos/talos_reduced.urdf",
                          RootJoint::FreeFlyer),
       {{"left_sole_link", 6}, {"right_sole_link", 6}}},
  };
  for (Setup& s : setups) {
    const Model& model = s.model;
    ContactSet contacts;
    for (const auto& [frame, dim] : s.contacts)
      contacts.add(model, frame, dim, ReferenceFrame::LocalWorldAligned, 0.0, 50.0);
    Data data(model);
    KnotData kd(model, contacts);
    std::mt19937 rng(3);
    const Eigen::VectorXd q = randomConfiguration(model, rng);
    const Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv);
    const Eigen::VectorXd tau = Eigen::VectorXd::Random(model.nv);
    const Eigen::VectorXd u = tau.tail(kd.nu);
    auto run = [&] {
      computeRNEADerivatives(model, data, q, v, tau);
      computeABADerivatives(model, data, q, v, tau);
      contactDynamicsDerivatives(model, data, contacts, kd.contact, q, v, tau);
      impulseDynamicsDerivatives(model, data, contacts, kd.contact, q, v);
      knotDynamicsDerivatives(model, data, contacts, kd, q, v, u, 0.01);
      contacts.setActive(0, false);  // a phase with one contact fewer
      knotDynamicsDerivatives(model, data, contacts, kd, q, v, u, 0.01);
      contacts.setActive(0, true);
    };
    run();
    long count;
    {
      AllocationCounter counter;
      run();
      count = counter.stop();
    }
    EXPECT_EQ(count, 0) << model.name;
  }
}

}  // namespace test_no_alloc
}  // namespace stride
