// Damped least-squares inverse kinematics (solver/multibody/inverse_kinematics.hpp): it converges
// on solo12's feet (positions) and talos_reduced's soles (placements, both error forms) from the
// standing posture to targets of a perturbed one; the damped step equals the primal form
// (Jᵀ J + μ I)⁻¹ Jᵀ e of the same minimization, and the Jacobians the error's central finite
// differences; a target out of reach fails with MaxIterations within bounded steps; bad targets
// and columns are refused; a step and a solve allocate nothing.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <random>

#include "solver/multibody/frames.hpp"
#include "solver/multibody/inverse_kinematics.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/srdf.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace test_inverse_kinematics {

const std::string kShared = STRIDE_SHARED_DIR;

struct Robot {
  Model model;
  std::vector<std::string> feet;
  int dim;
  Eigen::VectorXd q0;  // its standing posture
};

const Robot& solo() {
  static const Robot r = [] {
    Robot s{buildModelFromUrdf(kShared + "/robots/solo12/solo12.urdf", RootJoint::FreeFlyer),
            {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"},
            3,
            {}};
    loadReferenceConfigurations(s.model, kShared + "/robots/solo12/solo.srdf");
    s.q0 = s.model.referenceConfigurations.at("standing");
    return s;
  }();
  return r;
}

const Robot& talos() {
  static const Robot r = [] {
    Robot s{buildModelFromUrdf(kShared + "/robots/talos/talos_reduced.urdf", RootJoint::FreeFlyer),
            {"left_sole_link", "right_sole_link"},
            6,
            {}};
    loadReferenceConfigurations(s.model, kShared + "/robots/talos/talos.srdf");
    s.q0 = s.model.referenceConfigurations.at("half_sitting");
    return s;
  }();
  return r;
}

// The feet's placements at q as targets.
std::vector<IkTarget> targetsAt(const Robot& r, const Eigen::VectorXd& q, ReferenceFrame error) {
  Data data(r.model);
  framesForwardKinematics(r.model, data, q);
  std::vector<IkTarget> targets;
  for (const std::string& f : r.feet) {
    const int frame = r.model.getFrameId(f);
    targets.push_back({frame, r.dim, error, data.oMf[frame]});
  }
  return targets;
}

// The joints moved by up to `amplitude` rad each, the base where it is.
Eigen::VectorXd perturbed(const Robot& r, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  Eigen::VectorXd q = r.q0;
  for (int i = 7; i < r.model.nq; ++i) q[i] += u(rng);
  return q;
}

void expectConverges(const Robot& r, ReferenceFrame error) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Eigen::VectorXd q_target = perturbed(r, 0.2, seed);
    InverseKinematics ik(r.model, targetsAt(r, q_target, error),
                         InverseKinematics::jointColumns(r.model));
    Eigen::VectorXd q = r.q0;
    const IkResult result = ik.solve(q);
    ASSERT_TRUE(result.converged()) << toString(result.status) << " " << result.error;
    EXPECT_LT(result.error, 1e-10);
    EXPECT_GT(result.iterations, 1);
    EXPECT_LT(result.iterations, 20) << "Gauss-Newton converges in a few steps";
    EXPECT_EQ(q.head<7>(), r.q0.head<7>()) << "the base stays";
    Data data(r.model);
    framesForwardKinematics(r.model, data, q);
    for (int i = 0; i < ik.targets(); ++i) {
      const SE3& M = data.oMf[ik.target(i).frame];
      EXPECT_LT((M.p - ik.target(i).placement.p).norm(), 1e-10) << r.feet[i];
      if (r.dim == 6) {
        EXPECT_LT(log3(M.R.transpose() * ik.target(i).placement.R).norm(), 1e-10);
      }
    }
  }
}

TEST(InverseKinematics, ConvergesOnSolo12Feet) {
  expectConverges(solo(), ReferenceFrame::Local);
}

TEST(InverseKinematics, ConvergesOnTalosSoles) {
  expectConverges(talos(), ReferenceFrame::Local);
  expectConverges(talos(), ReferenceFrame::LocalWorldAligned);
}

// One step against the same minimization's primal form, dq = -(Jᵀ J + μ I)⁻¹ Jᵀ e (Jᵀ (J Jᵀ +
// μ I)⁻¹ = (Jᵀ J + μ I)⁻¹ Jᵀ), and the Jacobian against central differences of the error.
TEST(InverseKinematics, DampedStepAndJacobian) {
  struct Case {
    const Robot* robot;
    ReferenceFrame error;
  } cases[] = {{&solo(), ReferenceFrame::Local},
               {&talos(), ReferenceFrame::Local},
               {&talos(), ReferenceFrame::LocalWorldAligned}};
  for (const Case& c : cases) {
    const Robot& r = *c.robot;
    const std::vector<int> columns = InverseKinematics::jointColumns(r.model);
    InverseKinematicsOptions o;
    o.damping = 1e-3;  // large enough to matter
    InverseKinematics ik(r.model, targetsAt(r, perturbed(r, 0.1, 7), c.error), columns, o);
    Data data(r.model);
    computeJointJacobians(r.model, data, r.q0);
    Eigen::VectorXd dv(r.model.nv);
    const double norm = ik.stepFromKinematics(data, dv);
    const Eigen::MatrixXd J = ik.jacobian();
    const Eigen::VectorXd e = ik.error();
    EXPECT_NEAR(norm, e.norm(), 1e-15);
    const int n = static_cast<int>(columns.size());
    const Eigen::VectorXd primal =
        -(J.transpose() * J + o.damping * Eigen::MatrixXd::Identity(n, n))
             .ldlt()
             .solve(J.transpose() * e);
    EXPECT_TRUE(dv.head<6>().isZero(0.0)) << "the base does not move";
    EXPECT_LT((dv.tail(n) - primal).norm(), 1e-10 * primal.norm());
    // Damped: shorter than the undamped (pseudo-inverse) step, and a descent direction.
    const Eigen::VectorXd undamped = -J.transpose() * (J * J.transpose()).ldlt().solve(e);
    EXPECT_LT(dv.tail(n).norm(), undamped.norm());
    EXPECT_LT((J * dv.tail(n) + e).norm(), e.norm());

    // The Jacobian: the error's central differences along each column. The world-aligned
    // placement error is first order (its rotation rows are exact where the rotation error is
    // zero): its targets are the current orientations there.
    InverseKinematics at(r.model,
                         c.error == ReferenceFrame::Local ? targetsAt(r, perturbed(r, 0.1, 7), c.error)
                                                          : [&] {
                                                              auto t = targetsAt(r, r.q0, c.error);
                                                              for (auto& x : t)
                                                                x.placement.p.x() += 0.05;
                                                              return t;
                                                            }(),
                         columns, o);
    auto errorAt = [&](const Eigen::VectorXd& q) {
      Data d(r.model);
      computeJointJacobians(r.model, d, q);
      Eigen::VectorXd unused(r.model.nv);
      at.stepFromKinematics(d, unused);
      return Eigen::VectorXd(at.error());
    };
    errorAt(r.q0);
    const Eigen::MatrixXd J0 = at.jacobian();
    const double h = 1e-6;
    for (int k = 0; k < n; ++k) {
      Eigen::VectorXd step = Eigen::VectorXd::Zero(r.model.nv);
      step[columns[k]] = h;
      const Eigen::VectorXd plus = errorAt(integrate(r.model, r.q0, step));
      const Eigen::VectorXd minus = errorAt(integrate(r.model, r.q0, -step));
      EXPECT_LT(((plus - minus) / (2.0 * h) - J0.col(k)).norm(), 1e-7) << r.model.name << " " << k;
    }
  }
}

TEST(InverseKinematics, ATargetOutOfReachFails) {
  const Robot& r = solo();
  std::vector<IkTarget> targets = targetsAt(r, r.q0, ReferenceFrame::Local);
  targets[0].placement.p.z() -= 1.0;  // a metre below the front left foot: legs of 0.32 m
  InverseKinematicsOptions o;
  o.damping = 1e-4;
  o.max_iterations = 50;
  InverseKinematics ik(r.model, targets, InverseKinematics::jointColumns(r.model), o);
  Eigen::VectorXd q = r.q0;
  const IkResult result = ik.solve(q);
  EXPECT_FALSE(result.converged());
  EXPECT_EQ(result.status, IkStatus::MaxIterations) << toString(result.status);
  EXPECT_EQ(result.iterations, 50);
  EXPECT_GT(result.error, 0.5);  // still most of a metre short
  EXPECT_TRUE(q.allFinite()) << "the damping keeps the steps bounded at the straight leg";
  EXPECT_NE(std::string(toString(result.status)).find("reach"), std::string::npos);
}

TEST(InverseKinematics, RefusesBadTargetsAndColumns) {
  const Robot& r = solo();
  const std::vector<int> joints = InverseKinematics::jointColumns(r.model);
  const IkTarget foot{r.model.getFrameId("FL_FOOT"), 3, ReferenceFrame::Local, SE3()};
  EXPECT_NO_THROW(InverseKinematics(r.model, {foot}, joints));
  IkTarget bad = foot;
  bad.frame = -1;
  EXPECT_THROW(InverseKinematics(r.model, {bad}, joints), std::invalid_argument);
  bad = foot;
  bad.dim = 4;
  EXPECT_THROW(InverseKinematics(r.model, {bad}, joints), std::invalid_argument);
  bad = foot;
  bad.dim = 6;
  bad.error = ReferenceFrame::World;
  EXPECT_THROW(InverseKinematics(r.model, {bad}, joints), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(r.model, {}, joints), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(r.model, {foot}, {}), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(r.model, {foot}, {6, 6}), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(r.model, {foot}, {r.model.nv}), std::invalid_argument);
  InverseKinematics ik(r.model, {foot}, joints);
  Eigen::VectorXd q = r.q0.head(5);
  EXPECT_THROW(ik.solve(q), std::invalid_argument);
  EXPECT_EQ(joints.size(), 12u);
  EXPECT_EQ(joints.front(), 6);
}

TEST(InverseKinematics, StepAndSolveAllocateNothing) {
  const Robot& r = talos();
  InverseKinematics ik(r.model, targetsAt(r, perturbed(r, 0.1, 5), ReferenceFrame::Local),
                       InverseKinematics::jointColumns(r.model));
  Data data(r.model);
  Eigen::VectorXd dv(r.model.nv), q = r.q0;
  computeJointJacobians(r.model, data, q);
  long count;
  IkResult result;
  {
    test_support::AllocationCounter counter;
    ik.stepFromKinematics(data, dv);
    result = ik.solve(q);
    count = counter.stop();
  }
  EXPECT_TRUE(result.converged());
  EXPECT_EQ(count, 0);
}

}  // namespace test_inverse_kinematics
}  // namespace stride
