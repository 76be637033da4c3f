// What the mock robot senses, how its actuators act and how it differs from its description
// (sim/sensing.hpp, sim/actuators.hpp, sim/plant.hpp): each option changes what it says, by exactly
// what it says, seeded; everything off is the truth, untouched.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "sim/actuators.hpp"
#include "sim/plant.hpp"
#include "sim/sensing.hpp"
#include "sim_cases.hpp"

namespace stride {
namespace test_sensing {

const Robot& quad() {
  return sim_test::robot("stride_quad");
}

// A state that moves: joints and base at a known rate, t seconds in.
void moving(double t, Eigen::VectorXd& q, Eigen::VectorXd& v) {
  q = quad().default_q;
  v = Eigen::VectorXd::Zero(quad().model.nv);
  for (int j = 0; j < 12; ++j) {
    v[6 + j] = 0.5 + 0.1 * j;
    q[7 + j] += v[6 + j] * t;
  }
  v[0] = 0.3;
  q[0] += 0.3 * t;
}

struct Sampled {
  std::vector<Eigen::VectorXd> q, v;
};

Sampled sense(const sim::SensingOptions& o, int steps, std::uint64_t seed = 1) {
  sim::Sensing s(quad().model, o, 1e-3, seed);
  Eigen::VectorXd q, v;
  moving(0.0, q, v);
  s.reset(q, v);
  Sampled out;
  for (int k = 0; k < steps; ++k) {
    moving(k * 1e-3, q, v);
    s.sample(q, v);
    out.q.push_back(s.q());
    out.v.push_back(s.v());
  }
  return out;
}

double stddev(const std::vector<double>& x) {
  double m = 0, m2 = 0;
  for (double e : x) m += e;
  m /= x.size();
  for (double e : x) m2 += (e - m) * (e - m);
  return std::sqrt(m2 / x.size());
}

TEST(Sensing, OffIsTheTruthAndDrawsNothing) {
  sim::SensingOptions o;
  EXPECT_FALSE(o.enabled());
  sim::Sensing s(quad().model, o, 1e-3, 1);
  EXPECT_FALSE(s.enabled());
}

TEST(Sensing, EncoderResolutionQuantises) {
  sim::SensingOptions o;
  o.encoder_resolution = 2 * M_PI / 4096;  // a 12-bit encoder
  const Sampled s = sense(o, 50);
  Eigen::VectorXd q, v;
  for (int k = 0; k < 50; ++k) {
    moving(k * 1e-3, q, v);
    for (int j = 7; j < 19; ++j) {
      const double counts = s.q[k][j] / o.encoder_resolution;
      EXPECT_NEAR(counts, std::round(counts), 1e-9);
      EXPECT_LE(std::abs(s.q[k][j] - q[j]), 0.5 * o.encoder_resolution + 1e-12);
    }
    EXPECT_EQ(s.q[k].head(7), q.head(7));  // the base is not an encoder
    EXPECT_EQ(s.v[k], v);                  // measured velocities untouched
  }
}

TEST(Sensing, EncoderAndJointVelocityNoiseHaveTheirStdAndAreSeeded) {
  sim::SensingOptions o;
  o.encoder_noise = 0.005;
  o.joint_velocity_noise = 0.1;
  const Sampled a = sense(o, 2000, 5), b = sense(o, 2000, 5), c = sense(o, 2000, 6);
  EXPECT_EQ(a.q.back(), b.q.back());
  EXPECT_NE(a.q.back(), c.q.back());
  std::vector<double> eq, ev;
  Eigen::VectorXd q, v;
  for (int k = 0; k < 2000; ++k) {
    moving(k * 1e-3, q, v);
    eq.push_back(a.q[k][9] - q[9]);
    ev.push_back(a.v[k][8] - v[8]);
    EXPECT_EQ(a.q[k].head(7), q.head(7));
    EXPECT_EQ(a.v[k].head(6), v.head(6));
  }
  EXPECT_NEAR(stddev(eq), 0.005, 0.0005);
  EXPECT_NEAR(stddev(ev), 0.1, 0.01);
}

TEST(Sensing, JointVelocityFilterIsALowPassedDifferenceOfTheEncoders) {
  sim::SensingOptions o;
  o.joint_velocity_filter = 50.0;
  o.encoder_resolution = 1e-4;
  const Sampled s = sense(o, 300);
  Eigen::VectorXd q, v;
  moving(0.299, q, v);
  // A constant rate: the difference of 0.1 mrad counts over 1 ms, low-passed, settles on it.
  for (int j = 6; j < 18; ++j) EXPECT_NEAR(s.v.back()[j], v[j], 0.01) << j;
  // A step in the true rate reaches the estimate as 1 − (1 − α)^k.
  sim::SensingOptions f;
  f.joint_velocity_filter = 20.0;
  sim::Sensing step(quad().model, f, 1e-3, 1);
  Eigen::VectorXd q0 = quad().default_q, v0 = Eigen::VectorXd::Zero(18);
  step.reset(q0, v0);
  step.sample(q0, v0);  // at rest
  const double alpha = 1.0 - std::exp(-2.0 * M_PI * 20.0 * 1e-3);
  for (int k = 1; k <= 10; ++k) {
    q0[7] += 1e-3;        // 1 rad/s from here
    step.sample(q0, v0);  // v0 says 0: the filter does not read it
    EXPECT_NEAR(step.v()[6], 1.0 - std::pow(1.0 - alpha, k), 1e-9) << k;
  }
}

TEST(Sensing, LatencyShiftsByExactlyNSteps) {
  sim::SensingOptions o;
  o.latency = 3;
  const Sampled s = sense(o, 20);
  Eigen::VectorXd q, v, q0, v0;
  moving(0.0, q0, v0);
  for (int k = 0; k < 20; ++k) {
    moving((k - 3) * 1e-3, q, v);
    if (k < 3) {
      EXPECT_EQ(s.q[k], q0) << k;  // nothing older than the start
    } else {
      EXPECT_EQ(s.q[k], q) << k;
      EXPECT_EQ(s.v[k], v) << k;
    }
  }
}

TEST(Sensing, ImuOrientationNoiseGyroNoiseAndBiasDriftTheYawOnly) {
  sim::SensingOptions o;
  o.orientation_noise = 0.005;
  const Sampled s = sense(o, 2000);
  std::vector<double> angle;
  Eigen::VectorXd q, v;
  for (int k = 0; k < 2000; ++k) {
    moving(k * 1e-3, q, v);
    const Eigen::Quaterniond a(q[6], q[3], q[4], q[5]),
        b(s.q[k][6], s.q[k][3], s.q[k][4], s.q[k][5]);
    angle.push_back(a.angularDistance(b));
    EXPECT_NEAR(b.norm(), 1.0, 1e-12);
    EXPECT_EQ(s.q[k].head(3), q.head(3));
  }
  double mean = 0;
  for (double x : angle) mean += x;
  mean /= angle.size();
  // |n| of a 3-d Gaussian: σ √(8/π).
  EXPECT_NEAR(mean, 0.005 * std::sqrt(8.0 / M_PI), 0.0005);

  sim::SensingOptions g;
  g.gyro_noise = 0.02;
  g.gyro_bias_walk = 0.01;
  sim::Sensing imu(quad().model, g, 1e-3, 9);
  Eigen::VectorXd q0 = quad().default_q, v0 = Eigen::VectorXd::Zero(18);
  imu.reset(q0, v0);
  std::vector<double> wx;
  for (int k = 0; k < 10000; ++k) {
    imu.sample(q0, v0);
    wx.push_back(imu.v()[3] - imu.gyroBias().x());
    EXPECT_EQ(imu.v().head(3), v0.head(3));
  }
  EXPECT_NEAR(stddev(wx), 0.02, 0.002);
  EXPECT_GT(imu.gyroBias().norm(), 0.0);
  // After 10 s the yaw is off by the bias's integral; roll and pitch are not.
  const Eigen::Quaterniond est(imu.q()[6], imu.q()[3], imu.q()[4], imu.q()[5]);
  const Eigen::Vector3d z = est * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(z.z(), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(2 * std::atan2(est.z(), est.w())), std::abs(imu.yawDrift()), 1e-9);
  EXPECT_GT(std::abs(imu.yawDrift()), 1e-4);
}

TEST(Sensing, BasePositionVelocityNoiseAndDriftOnXYOnly) {
  sim::SensingOptions o;
  o.base_position_noise = 0.005;
  o.base_velocity_noise = 0.05;
  o.base_drift = 0.01;
  const Sampled s = sense(o, 4000);
  std::vector<double> ez, ev;
  Eigen::VectorXd q, v;
  for (int k = 0; k < 4000; ++k) {
    moving(k * 1e-3, q, v);
    ez.push_back(s.q[k][2] - q[2]);
    ev.push_back(s.v[k][1] - v[1]);
    EXPECT_EQ(s.q[k].tail(12), q.tail(12));
  }
  EXPECT_NEAR(stddev(ez), 0.005, 0.0005);  // z: noise, no drift
  EXPECT_NEAR(stddev(ev), 0.05, 0.005);
  // The drift alone: x and y wander as a random walk (std σ √t after t, over seeds), z not.
  sim::SensingOptions d;
  d.base_drift = 0.01;
  std::vector<double> ex;
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    const Sampled w = sense(d, 1000, seed);
    moving(0.999, q, v);
    ex.push_back(w.q.back()[0] - q[0]);
    EXPECT_EQ(w.q.back()[2], q[2]);
    EXPECT_NE(w.q.back()[1], q[1]);
  }
  EXPECT_NEAR(stddev(ex), 0.01, 0.001);
}

TEST(Sensing, TheVelocityEstimatorFiltersTheLegsNoiseAndFollowsTheAccelerometer) {
  const Robot& r = quad();
  const double dt = 1e-3, kappa = 1.0 - std::exp(-2.0 * M_PI * 5.0 * dt);
  auto run = [&](double legs, double accel, double a_true) {
    sim::SensingOptions o;
    o.base_velocity_noise = legs;
    o.accel_noise = accel;
    o.velocity_estimator = 5.0;
    sim::Sensing s(r.model, o, dt, 4);
    Eigen::VectorXd q = r.default_q, v = Eigen::VectorXd::Zero(18);
    s.reset(q, v);
    std::vector<double> error;
    for (int k = 0; k < 20000; ++k) {
      v[0] = a_true * k * dt;  // a level base: base and world axes agree
      s.sample(q, v);
      error.push_back(s.v()[0] - v[0]);
    }
    return error;
  };
  // The legs' white noise, low-passed: σ √(κ / (2 − κ)), an eighth of it at 5 Hz.
  EXPECT_NEAR(stddev(run(0.05, 0.0, 0.0)), 0.05 * std::sqrt(kappa / (2.0 - kappa)), 0.0006);
  // The accelerometer's, integrated and leaked: about dt σ / √(2κ).
  EXPECT_NEAR(stddev(run(0.0, 0.05, 0.0)), dt * 0.05 / std::sqrt(2.0 * kappa), 3e-5);
  // Noise-free, an accelerating base is followed exactly (the accelerometer sees the ramp).
  for (double e : run(0.0, 0.0, 1.0)) EXPECT_NEAR(e, 0.0, 1e-9);
}

TEST(Sensing, ADroppedSampleKeepsThePreviousEstimate) {
  sim::SensingOptions o;
  o.sample_drop = 0.3;
  sim::Sensing s(quad().model, o, 1e-3, 2);
  Eigen::VectorXd q, v;
  moving(0.0, q, v);
  s.reset(q, v);
  int kept = 0;
  for (int k = 0; k < 1000; ++k) {
    const Eigen::VectorXd before = s.q();
    moving(k * 1e-3, q, v);
    s.sample(q, v);
    if (s.q() == before && k > 0)
      ++kept;
    else
      EXPECT_EQ(s.q(), q);
  }
  EXPECT_EQ(kept, s.dropped());
  EXPECT_NEAR(s.dropped() / 1000.0, 0.3, 0.05);
}

TEST(Sensing, BadOptionsAreRefused) {
  sim::SensingOptions o;
  o.encoder_noise = -1;
  EXPECT_THROW(o.check(), std::invalid_argument);
  o = {};
  o.latency = -1;
  EXPECT_THROW(o.check(), std::invalid_argument);
  o = {};
  o.sample_drop = 1.5;
  EXPECT_THROW(o.check(), std::invalid_argument);
  o = {};
  o.gyro_noise = std::nan("");
  EXPECT_THROW(o.check(), std::invalid_argument);
  o = {};
  o.accel_noise = -0.1;
  EXPECT_THROW(o.check(), std::invalid_argument);
  o = {};
  o.velocity_estimator = std::numeric_limits<double>::infinity();
  EXPECT_THROW(o.check(), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
Eigen::VectorXd actuate(const sim::ActuatorOptions& o, const Eigen::VectorXd& cmd,
                        const Eigen::VectorXd& v, int steps) {
  sim::Actuators a(quad().model, quad().default_q, o, 1e-3);
  Eigen::VectorXd tau(12);
  for (int k = 0; k < steps; ++k) a.apply(cmd, v, tau);
  return tau;
}

TEST(Actuators, OffPassesTheCommand) {
  const Eigen::VectorXd cmd = Eigen::VectorXd::LinSpaced(12, -3, 3);
  EXPECT_EQ(actuate({}, cmd, Eigen::VectorXd::Ones(18), 1), cmd);
}

TEST(Actuators, LatencyShiftsTheCommandByExactlyNSteps) {
  sim::ActuatorOptions o;
  o.latency = 4;
  sim::Actuators a(quad().model, quad().default_q, o, 1e-3);
  Eigen::VectorXd tau(12);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(18);
  for (int k = 0; k < 12; ++k) {
    a.apply(Eigen::VectorXd::Constant(12, k + 1.0), v, tau);
    EXPECT_EQ(tau[0], k >= 4 ? k - 3.0 : 0.0) << k;
  }
}

TEST(Actuators, BandwidthIsAFirstOrderLag) {
  sim::ActuatorOptions o;
  o.bandwidth = 30.0;
  const double alpha = 1.0 - std::exp(-2.0 * M_PI * 30.0 * 1e-3);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(18), cmd = Eigen::VectorXd::Constant(12, 2.0);
  for (int k : {1, 5, 20})
    EXPECT_NEAR(actuate(o, cmd, v, k)[3], 2.0 * (1.0 - std::pow(1.0 - alpha, k)), 1e-12) << k;
}

TEST(Actuators, TorqueScaleAndTheTorqueSpeedEnvelope) {
  sim::ActuatorOptions o;
  o.torque_scale = 0.8;
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(18), cmd = Eigen::VectorXd::Constant(12, 2.0);
  EXPECT_NEAR(actuate(o, cmd, v, 1)[0], 1.6, 1e-15);
  sim::ActuatorOptions e;
  e.velocity_limits = true;
  const Model& m = quad().model;
  const double wmax = m.velocityLimit[6], tmax = m.effortLimit[6];
  ASSERT_TRUE(std::isfinite(wmax) && wmax > 0.0) << "stride_quad's URDF gives velocity limits";
  Eigen::VectorXd w = Eigen::VectorXd::Zero(18);
  const Eigen::VectorXd big = Eigen::VectorXd::Constant(12, 10 * tmax);
  w[6] = 0.5 * wmax;  // half speed, pushing on: half the stall torque left
  EXPECT_NEAR(actuate(e, big, w, 1)[0], 0.5 * tmax, 1e-9);
  EXPECT_NEAR(actuate(e, -big, w, 1)[0], -10 * tmax, 1e-9);  // braking: the command (clamped later)
  w[6] = 1.2 * wmax;  // past the no-load speed: no torque to go faster
  EXPECT_EQ(actuate(e, big, w, 1)[0], 0.0);
  EXPECT_NEAR(actuate(e, 0.1 * big, Eigen::VectorXd::Zero(18), 1)[0], tmax, 1e-12);
}

TEST(Actuators, FrictionAndDampingOpposeTheMotionAndNeverReverseIt) {
  sim::ActuatorOptions o;
  o.friction = 0.3;
  o.damping = 0.1;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(18);
  w[6] = 2.0;
  w[7] = -2.0;
  w[8] = 1e-6;  // nearly at rest: capped at what stops it in one step
  const Eigen::VectorXd tau = actuate(o, Eigen::VectorXd::Zero(12), w, 1);
  EXPECT_NEAR(tau[0], -0.5, 1e-12);
  EXPECT_NEAR(tau[1], 0.5, 1e-12);
  EXPECT_LT(tau[2], 0.0);
  EXPECT_GT(tau[2], -0.3);
  EXPECT_EQ(tau[3], 0.0);  // at rest: nothing
}

// ---------------------------------------------------------------------------------------------
TEST(Plant, MassScalePayloadComOffsetAndTorqueLimits) {
  const Robot& r = quad();
  sim::PlantOptions o;
  o.mass_scale = {{"", 1.2}};
  EXPECT_NEAR(sim::plantOf(r, o).model.totalMass(), 1.2 * r.model.totalMass(), 1e-9);
  std::string base_link;
  for (const Frame& f : r.model.frames)
    if (f.type == FrameType::Body && f.parentJoint == 1 && base_link.empty()) base_link = f.name;
  ASSERT_FALSE(base_link.empty());
  o.mass_scale = {{base_link, 2.0}};
  const Robot heavy = sim::plantOf(r, o);
  EXPECT_NEAR(heavy.model.totalMass() - r.model.totalMass(), r.model.inertias[1].m, 1e-9);
  EXPECT_EQ(heavy.model.inertias[2].m, r.model.inertias[2].m);
  o.mass_scale = {{"no_such_link", 2.0}};
  EXPECT_THROW(sim::plantOf(r, o), std::invalid_argument);

  sim::PlantOptions p;
  p.payload = 2.0;
  p.payload_at = Eigen::Vector3d(0.03, 0.0, 0.05);
  const Robot loaded = sim::plantOf(r, p);
  EXPECT_NEAR(loaded.model.totalMass(), r.model.totalMass() + 2.0, 1e-12);
  const double m0 = r.model.inertias[1].m;
  EXPECT_NEAR(loaded.model.inertias[1].com().x(),
              (m0 * r.model.inertias[1].com().x() + 2.0 * 0.03) / (m0 + 2.0), 1e-12);

  sim::PlantOptions c;
  c.com_offset = Eigen::Vector3d(0.02, -0.01, 0.0);
  const Robot shifted = sim::plantOf(r, c);
  EXPECT_TRUE(shifted.model.inertias[1].com().isApprox(r.model.inertias[1].com() + c.com_offset));
  EXPECT_NEAR(shifted.model.inertias[1].m, m0, 0.0);
  EXPECT_TRUE(shifted.model.inertias[1].inertiaAboutCom().isApprox(
      r.model.inertias[1].inertiaAboutCom(), 1e-12));

  sim::PlantOptions t;
  t.torque_limit_scale = 0.8;
  const Robot weak = sim::plantOf(r, t);
  EXPECT_TRUE(weak.model.effortLimit.tail(12).isApprox(0.8 * r.model.effortLimit.tail(12)));
}

TEST(Plant, MassScaleText) {
  std::pair<std::string, double> s;
  EXPECT_TRUE(sim::parseMassScale("1.2", s));
  EXPECT_EQ(s.first, "");
  EXPECT_EQ(s.second, 1.2);
  EXPECT_TRUE(sim::parseMassScale("base_link:0.8", s));
  EXPECT_EQ(s.first, "base_link");
  EXPECT_EQ(s.second, 0.8);
  for (const char* bad : {"", ":1", "base:", "base:-1", "base:0", "x", "1.2abc", "base:nan"})
    EXPECT_FALSE(sim::parseMassScale(bad, s)) << bad;
}

}  // namespace test_sensing
}  // namespace stride
