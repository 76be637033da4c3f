// After construction, Simulator::step (with and without contacts, clamping, NaN rejection and an
// external wrench), the policy evaluation, the hold policy and the disturbance helpers touch no
// heap: malloc and its relatives are counted (tests/allocation_counter.hpp), with Eigen's own check
// armed as well; the interposition is per binary, hence this separate executable.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <stdlib.h>

#include <cmath>
#include <random>

#include "config/model_hash.hpp"
#include "messages/signing.hpp"
#include "sim/actuators.hpp"
#include "sim/disturbances.hpp"
#include "sim/sensing.hpp"
#include "sim/sim_node.hpp"
#include "sim_cases.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {
namespace test_sim_no_alloc {

using test_support::allocations;

TEST(SimNoAllocation, CounterSeesAllocations) {
  EXPECT_GE(allocations([] {
              Eigen::internal::set_is_malloc_allowed(true);
              std::vector<int> v(10);
              int* volatile data = v.data();  // volatile: clang may drop an unused allocation
              (void)data;
            }),
            1);
}

TEST(SimNoAllocation, Step) {
  for (const char* name : {"stride_quad", "stride_humanoid"}) {
    const Robot& r = sim_test::robot(name);
    for (int substeps : {1, 3}) {
      sim::SimOptions opt;
      opt.substeps = substeps;
      sim::Simulator sim(r, opt);
      // Dropped from 2 cm: the steps see flight, touch-downs and resting contact.
      Eigen::VectorXd q = r.default_q;
      q[2] += 0.02;
      sim.reset(q, Eigen::VectorXd::Zero(r.model.nv));
      const sim::HoldPolicy hold = sim_test::holdDefault(r);
      Eigen::VectorXd tau(sim.nu()), bad = Eigen::VectorXd::Constant(sim.nu(), std::nan(""));
      Eigen::VectorXd big = Eigen::VectorXd::Constant(sim.nu(), 1e4);
      Vector6d push = Vector6d::Zero();
      push[0] = 1.0;
      sim.applyExternalWrench(push, 0.05);
      const long n = allocations([&] {
        for (int i = 0; i < 200; ++i) {
          hold.torque(r.model, sim.q(), sim.v(), tau);
          sim.step(i == 50 ? bad : i == 60 ? big : tau);
        }
      });
      EXPECT_EQ(n, 0) << name << ", substeps " << substeps;
      EXPECT_EQ(sim.counters().rejected_torques, 1);
      EXPECT_GE(sim.counters().clamped_steps, 1);
      EXPECT_GT(sim.totalNormalForce(), 0.0) << name << ": the contacts were exercised";
    }
  }
}

TEST(SimNoAllocation, PolicyAndDisturbances) {
  const Robot& r = sim_test::robot("stride_quad");
  const Model& model = r.model;
  msg::Policy p;
  p.resize(5, model.nq, model.nv, 12);
  p.dt = 0.01;
  std::mt19937 rng(1);
  for (int k = 0; k < p.knots; ++k) {
    Eigen::Map<Eigen::VectorXd>(p.xRef(k), model.nq) = randomConfiguration(model, rng);
    for (size_t i = 0; i < p.K.size(); ++i) p.K[i] = 0.01 * static_cast<double>(i % 7);
  }
  msg::PolicyEvaluator eval(model, 12);
  const sim::HoldPolicy hold(model, r.default_q, 5.0, 0.1);
  std::vector<sim::StandDownContact> contacts;
  for (const ContactSpec& c : r.contacts) contacts.push_back({model.getFrameId(c.frame), c.dim});
  sim::StandDown down(model, hold, contacts, sim::StandDownOptions{});
  sim::SensingOptions so;
  so.encoder_resolution = 1e-4;
  so.encoder_noise = so.joint_velocity_noise = so.orientation_noise = so.gyro_noise = 0.01;
  so.gyro_bias_walk = so.base_position_noise = so.base_velocity_noise = so.base_drift = 0.01;
  so.joint_velocity_filter = 100.0;
  so.latency = 3;
  so.sample_drop = 0.2;
  sim::Sensing sensing(model, so, 1e-3, 3);
  sensing.reset(r.default_q, Eigen::VectorXd::Zero(model.nv));
  sim::ActuatorOptions ao;
  ao.latency = 2;
  ao.bandwidth = 100.0;
  ao.torque_scale = 0.9;
  ao.velocity_limits = true;
  ao.friction = 0.1;
  ao.damping = 0.01;
  sim::Actuators actuators(model, r.default_q, ao, 1e-3);
  Eigen::VectorXd tau_out(12);
  sim::StateDelay delay(model.nq, model.nv, 4);
  sim::MessageDropper dropper(0.3, 4);
  sim::PushSchedule pushes;
  pushes.pushes.push_back({0.01, 0.02, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero()});
  Eigen::VectorXd q = r.default_q, v = Eigen::VectorXd::Zero(model.nv), tau(12);
  Eigen::VectorXd qd(model.nq), vd(model.nv);
  double td, sink = 0;
  const long n = allocations([&] {
    for (int i = 0; i < 80; ++i) {
      const double t = -0.01 + 0.001 * i;  // before, during and after the policy
      eval.evaluate(p, t, q, v, tau);
      if (i == 40) down.begin(t, q, tau);
      if (i >= 40) down.torque(t, q, v, i < 60 ? 0b0110u : 0b1111u, tau);
      sensing.sample(q, v);
      sink += sensing.q().sum() + sensing.v().sum();
      actuators.apply(tau, v, tau_out);
      sink += tau_out.sum();
      delay.push(t, q, v);
      if (delay.delayed(td, qd, vd)) sink += td;
      sink += dropper.drop();
      sink += pushes.wrenchAt(t).sum() + pushes.activeUntil(t);
    }
  });
  EXPECT_EQ(n, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

// The robot's node with a key (messages/README.md, "Signing"): signing each state it publishes and
// checking each policy it takes allocate nothing.
TEST(SimNoAllocation, SignedStatesAndPolicies) {
  const Robot& r = sim_test::robot("stride_quad");
  char dir[] = "/tmp/stride-key-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/key";
  msg::writeNewKeyFile(path);
  struct Sink : Publisher {
    long bytes = 0;
    void publish(const std::string&, const void*, int size) override { bytes += size; }
  } out;
  sim::SimNodeOptions options;
  options.key = msg::loadKeyFile(path);
  sim::SimNode node(r, sim::SimOptions{}, options, out);
  node.reset(r.default_q, Eigen::VectorXd::Zero(r.model.nv));
  msg::Signer controller(*options.key, 21);
  policy_t p{};
  msg::shape(p, 4, r.model.nq, r.model.nv, 12);
  p.status = p.phase = 0;
  p.tick = 0;
  p.t0 = 0.0;
  p.model_hash = modelHash(r);
  p.source_id = 1;
  p.session = node.session();
  p.dt = 0.01;
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < r.model.nq; ++i) p.x_ref[k][i] = r.default_q[i];
  std::vector<std::uint8_t> bytes(p.getEncodedSize() + msg::kSignatureSize);
  const auto policyAt = [&](std::int64_t utime) {
    p.utime = p.knot0_utime = utime;
    const int n = p.encode(bytes.data(), 0, p.getEncodedSize());
    const int size =
        controller.sign("STRIDE_POLICY", bytes.data(), n, static_cast<int>(bytes.size()));
    lcm::ReceiveBuffer rbuf{bytes.data(), static_cast<uint32_t>(size), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
  };
  policyAt(node.publishState());  // the first policy sizes the robot's copy
  const long n = allocations([&] {
    for (int i = 0; i < 20; ++i) policyAt(node.publishState());
  });
  EXPECT_EQ(n, 0);
  EXPECT_EQ(node.stats().policies, 21);
  EXPECT_EQ(node.stats().policies_unauthenticated, 0);
}

}  // namespace test_sim_no_alloc
}  // namespace stride
