// stride-sim's LCM side (sim/sim_node.hpp): the wire contract on the robot's end. States carry the
// robot's model hash; a policy of another model is refused, counted, and each cause said once.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "config/model_hash.hpp"
#include "sim/sim_node.hpp"
#include "sim_cases.hpp"

namespace stride {
namespace {

struct Sink : Publisher {
  robot_state_t state;
  void publish(const std::string&, const void* data, int size) override {
    state.decode(data, 0, size);
  }
};

std::vector<unsigned char> encode(const policy_t& p) {
  std::vector<unsigned char> b(p.getEncodedSize());
  p.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// A policy that holds the default posture, in `robot`'s sizes, stamped with `hash`.
policy_t holdPolicy(const Robot& robot, int nq, int nv, std::int64_t hash) {
  policy_t p;
  msg::shape(p, 2, nq, nv, nv - 6);
  p.model_hash = hash;
  p.source_id = 1;
  p.utime = p.knot0_utime = 1000000;
  p.dt = 0.01;
  p.status = 0;
  for (int k = 0; k < 2; ++k) {
    p.x_ref[k][6] = 1.0;  // a unit quaternion in any size
    for (int i = 0; i < std::min(nq, robot.model.nq); ++i) p.x_ref[k][i] = robot.default_q[i];
  }
  return p;
}

TEST(SimNode, StatesCarryTheModelHashAndAnotherModelsPoliciesAreRefused) {
  const Robot& robot = sim_test::robot("stride_quad");
  Sink out;
  sim::SimNode node(robot, sim::SimOptions{}, sim::SimNodeOptions{}, out);
  node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  ASSERT_GE(node.publishState(), 0);
  EXPECT_EQ(out.state.model_hash, modelHash(robot));

  auto feed = [&](const policy_t& p) {
    std::vector<unsigned char> b = encode(p);
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
  };
  char ours[17];
  msg::formatHash(modelHash(robot), ours);
  testing::internal::CaptureStderr();
  feed(holdPolicy(robot, 19, 18, modelHash(robot) ^ 1));  // same sizes, another layout
  feed(holdPolicy(robot, 19, 18, modelHash(robot) ^ 1));
  feed(holdPolicy(robot, 29, 28, 99));  // another robot's sizes
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.stats().policies, 0);
  EXPECT_EQ(node.stats().policies_rejected, 3);
  EXPECT_EQ(node.stats().policies_wrong_model, 3);
  // Each cause once, saying what was expected and what came.
  EXPECT_NE(err.find("stride-sim: refused a policy on 'STRIDE_POLICY': expected hash " +
                     std::string(ours) + " (stride_quad, nq 19, nv 18), got hash"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("expected nq 19, nv 18 (stride_quad, hash " + std::string(ours) +
                     "), got nq 29, nv 28 (hash 0000000000000063)"),
            std::string::npos)
      << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 2) << err;

  feed(holdPolicy(robot, 19, 18, modelHash(robot)));
  EXPECT_EQ(node.stats().policies, 1);
  EXPECT_TRUE(node.answered(1000000));
}

}  // namespace
}  // namespace stride
