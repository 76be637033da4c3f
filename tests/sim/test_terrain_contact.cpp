// The mock robot on terrain (sim/simulator.hpp with SimOptions::terrain, terrain/terrain.hpp):
// a flat terrain gives the very bits the simulator gave before terrains existed; the quadruped
// rests on a box top at its standing height; a sled stays put on a 20° ramp with μ = 1 and slides
// down it at g (sin θ − μ cos θ) with μ = 0.1; a point swept into a 10 cm riser is stopped at its
// plane and counted as a trip; footholds: the distance of a place to the terrain's edges (stairs,
// a ramp's side), a puck or a sled dropped onto a tread near its nosing or mid-tread counted as
// edge footholds or not, never on flat ground; step() allocates nothing on stairs and rough ground.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <string>

#include "sim_cases.hpp"
#include "terrain/terrain.hpp"

namespace stride {
namespace test_terrain_contact {

using sim::SimOptions;
using sim::Simulator;
using sim::StepStatus;
using sim_test::robot;
using terrain::Terrain;
using terrain::TerrainSpec;

constexpr double kG = 9.81;
constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Golden final states of the simulator before terrains (commit 2233219: flat ground only), printed
// with %a by a throwaway program linked against that commit's stride_sim and running exactly
// flatScenario() below. Built with the repository's Release flags, -march=native on a host with
// AVX-512 and FMA: GCC contracts a * b + c into FMAs, so another instruction set rounds otherwise,
// old and new code alike; on such a host, regenerate them from that commit.
// stride_quad substeps 1 ground 0: base z 0.221969, normal force 24.507, pgs_unconverged 0
constexpr double kQuadQ[] = {
    0x1.b2acd1c6e4693p-5,   0x1.04041d89c843fp-36, 0x1.c697c46cbb9e7p-3,   0x1.8d95f379880d7p-37,
    -0x1.9888017ae075ap-13, 0x1.a852193bb510ep-35, 0x1.ffffff5d038cbp-1,   0x1.59de1f7036a3ep-14,
    0x1.99003f5ee1cf3p-1,   -0x1.9b9870c181513p+0, -0x1.59de1a01ee19ep-14, 0x1.99003f5ee0164p-1,
    -0x1.9b9870c18b06ep+0,  0x1.290fa791422f3p-15, 0x1.992f65444fa64p-1,   -0x1.9bed7f7be4d8cp+0,
    -0x1.290fa66e4288cp-15, 0x1.992f65445f18cp-1,  -0x1.9bed7f7c00206p+0};
constexpr double kQuadV[] = {-0x1.5830d1d533242p-12, 0x1.84a703eb193b3p-35,  -0x1.f289a6223cbap-14,
                             -0x1.87167800587cfp-32, -0x1.91ddd6d70ed68p-12, -0x1.83e2d1ae415aep-36,
                             0x1.3d551a6cp-26,       -0x1.d9a785cabfp-11,    -0x1.93f220dc81p-12,
                             -0x1.3aa64924p-26,      -0x1.d9a789eb2b4p-11,   -0x1.93f214a905p-12,
                             0x1.1412df34p-25,       -0x1.225b7a11a78p-12,   -0x1.afdb1b4d228p-10,
                             -0x1.12beb662p-25,      -0x1.225b8f740a8p-12,   -0x1.afdb11c2348p-10};

// stride_humanoid substeps 1 ground 0: base z 0.801003, normal force 594.298, pgs_unconverged 4
constexpr double kHumanoidQ[] = {
    0x1.56eec706f42ecp-10,  0x1.e6def103f447p-29,  0x1.9a1d1e5bf49ecp-1,   -0x1.03f83166fd12ep-30,
    0x1.f83efc0b2ddd4p-13,  0x1.3e48d2d910d1p-31,  0x1.ffffff07b1fbdp-1,   0x1.379aaac0cd5b8p-35,
    -0x1.587256770409bp-29, -0x1.00a4544273184p-2, 0x1.025a335b47da3p-1,   -0x1.048e221090116p-2,
    -0x1.b2469f1d4ab2ep-29, 0x1.1874d2da7ec16p-32, -0x1.1d8bb67d12cdap-29, -0x1.00a45421b0954p-2,
    0x1.025a333fab97bp-1,   -0x1.048e21fef36a8p-2, -0x1.819cff493bb99p-28, -0x1.abd0108c0b298p-36,
    0x1.cbb1d36dc7785p-11,  0x1.95019d068f553p-13, 0x1.ef3aef513faf9p-37,  0x1.78be2fd42390cp-38,
    -0x1.32f8cd7ad6096p-2,  0x1.95019f25296a9p-13, 0x1.ef3aeee77989fp-37,  0x1.78be2fbb2fbb2p-38,
    -0x1.32f8cd7ac2519p-2};
constexpr double kHumanoidV[] = {
    0x1.39329219bbb1p-5,    0x1.14c4debe8e9d9p-24,  0x1.483c27c9290f4p-10, -0x1.28dd6ceb7245ap-25,
    0x1.1e3296799d09dp-4,   0x1.7249226ae0cbep-27,  -0x1.23b8b4508abp-31,  -0x1.b5b2677898f9ep-25,
    -0x1.4162c72ced2bp-7,   -0x1.1cf3fb4adec6p-6,   -0x1.5d927c8a9ef2p-5,  0x1.31f214f388ap-30,
    0x1.73a44ebbe86cp-29,   -0x1.9733be47888bep-25, -0x1.41626b193429p-7,  -0x1.1cf451e680cap-6,
    -0x1.5d9268465fa8p-5,   -0x1.460e4906b15cp-26,  0x1.515e3fa43ap-36,    0x1.47cc03302c30cp-7,
    -0x1.047bbe638b38ap-10, 0x1.21ec653b764dap-29,  0x1.91e51acbb32dp-31,  -0x1.9d8446687dep-13,
    -0x1.047bb52cdf1a6p-10, 0x1.21ec6540befb9p-29,  0x1.91e51af02baf8p-31, -0x1.9d842700a758p-13};

// stride_quad substeps 2 ground 0.05: base z 0.271970, normal force 24.499, pgs_unconverged 0
constexpr double kQuadRaisedGroundQ[] = {
    0x1.b01a8c52c76fap-5,   0x1.352ca2d34523p-38,   0x1.167f5461284a7p-2,   0x1.dcad5e2bbdaf9p-40,
    -0x1.452b836a36f03p-12, -0x1.d3099874c0526p-38, 0x1.fffffe62f87c5p-1,   0x1.238b0a284b754p-15,
    0x1.994df40e95aadp-1,   -0x1.9b806c8506ecfp+0,  -0x1.238b07ca87ba3p-15, 0x1.994df40e91d2dp-1,
    -0x1.9b806c85062fep+0,  0x1.d14c0d3beecdep-15,  0x1.98e2ca3a30b9fp-1,   -0x1.9c04a27610169p+0,
    -0x1.d14c0d85d71e7p-15, 0x1.98e2ca3a3e8f6p-1,   -0x1.9c04a27617504p+0};
constexpr double kQuadRaisedGroundV[] = {
    -0x1.762f82e8ba5e4p-13, -0x1.2b4b89b644096p-37, -0x1.80d0229157c9p-14, -0x1.e00b735cb4a28p-37,
    -0x1.099e319e86f04p-12, -0x1.ac29f6abf4107p-35, 0x1.06281f68p-27,      -0x1.7ea7423cdf4p-12,
    -0x1.8608e12a53p-12,    -0x1.033ab568p-27,      -0x1.7ea73ee9f9cp-12,  -0x1.8608ef9c4a8p-12,
    0x1.34913f76p-25,       0x1.8a7d19cd3fp-15,     -0x1.3b823d79fep-10,   -0x1.34055fbcp-25,
    0x1.8a7d080686p-15,     -0x1.3b823db0f7cp-10};

// Dropped from 2 cm above the default posture onto the ground at `ground`, the joints held at the
// default posture by a PD (the gains of sim_cases.hpp, written out: the golden values depend on
// them), pushed by 20 N along x from 0.5 s to 0.7 s, 1.5 s in all.
void flatScenario(const Robot& r, int substeps, double ground,
                  std::shared_ptr<const Terrain> terrain, Eigen::VectorXd& q_end,
                  Eigen::VectorXd& v_end) {
  const bool quad = r.name == "stride_quad";
  SimOptions opt;
  opt.substeps = substeps;
  opt.ground_height = terrain ? 0.0 : ground;
  opt.terrain = std::move(terrain);
  Simulator sim(r, opt);
  Eigen::VectorXd q = r.default_q;
  q[2] += 0.02 + ground;
  sim.reset(q, Eigen::VectorXd::Zero(r.model.nv));
  const sim::HoldPolicy hold(r.model, r.default_q, quad ? 100.0 : 3000.0, quad ? 2.0 : 30.0, 1e-3);
  Eigen::VectorXd tau(sim.nu());
  Vector6d push = Vector6d::Zero();
  push[0] = 20.0;
  for (int i = 0; i < 1500; ++i) {
    if (i == 500) sim.applyExternalWrench(push, 0.7);
    hold.torque(r.model, sim.q(), sim.v(), tau);
    sim.step(tau);
  }
  q_end = sim.q();
  v_end = sim.v();
}

// The goldens are the pre-terrain code's q and v, made by its Release build on one machine. With
// -march=native the bits are the building CPU's (GCC's FMA contraction and vectorization follow
// its instruction set and tuning: an Intel Xeon with AVX-512 and the AMD EPYC the goldens came
// from differ by ~1e-14 after these 1.5 s), and another compiler rounds otherwise again: so the
// runs must agree with the goldens to 1e-9 (the same physics), and the three flat worlds with each
// other bit for bit (below), on any machine.
constexpr double kGoldenTolerance = 1e-9;

void expectBits(const Eigen::VectorXd& got, const double* golden, size_t n, const char* what) {
  ASSERT_EQ(static_cast<size_t>(got.size()), n) << what;
  int differ = 0;
  for (size_t k = 0; k < n; ++k)
    if (!(std::abs(got[k] - golden[k]) <= kGoldenTolerance)) {
      if (++differ <= 3)
        ADD_FAILURE() << what << "[" << k << "]: " << std::hexfloat << got[k] << " != " << golden[k]
                      << std::defaultfloat << " (" << got[k] - golden[k] << ")";
    }
  EXPECT_EQ(differ, 0) << what << ": entries that differ";
}

TEST(TerrainContact, FlatTerrainGivesThePreTerrainBits) {
  struct Case {
    const char* robot;
    int substeps;
    double ground;
    const double *q, *v;
    size_t nq, nv;
  };
  const Case cases[] = {
      {"stride_quad", 1, 0.0, kQuadQ, kQuadV, std::size(kQuadQ), std::size(kQuadV)},
      {"stride_humanoid", 1, 0.0, kHumanoidQ, kHumanoidV, std::size(kHumanoidQ),
       std::size(kHumanoidV)},
      {"stride_quad", 2, 0.05, kQuadRaisedGroundQ, kQuadRaisedGroundV,
       std::size(kQuadRaisedGroundQ), std::size(kQuadRaisedGroundV)},
  };
  for (const Case& c : cases) {
    const Robot& r = robot(c.robot);
    // No terrain (the ground at ground_height), a flat Terrain, and a spec with nothing on it.
    const std::shared_ptr<const Terrain> worlds[] = {nullptr, std::make_shared<Terrain>(c.ground),
                                                     std::make_shared<Terrain>([&] {
                                                       TerrainSpec s;
                                                       s.ground = c.ground;
                                                       return s;
                                                     }())};
    Eigen::VectorXd q_first, v_first;
    for (const auto& world : worlds) {
      SCOPED_TRACE(std::string(c.robot) + ", substeps " + std::to_string(c.substeps) + ", ground " +
                   std::to_string(c.ground) + (world ? ", a flat Terrain" : ", no terrain"));
      Eigen::VectorXd q, v;
      flatScenario(r, c.substeps, c.ground, world, q, v);
      expectBits(q, c.q, c.nq, "q");
      expectBits(v, c.v, c.nv, "v");
      if (q_first.size() == 0) {
        q_first = q;
        v_first = v;
      }
      for (Eigen::Index k = 0; k < q.size(); ++k) EXPECT_EQ(q[k], q_first[k]) << "q[" << k << "]";
      for (Eigen::Index k = 0; k < v.size(); ++k) EXPECT_EQ(v[k], v_first[k]) << "v[" << k << "]";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// stride_quad dropped from 2 cm onto a box 0.15 m high (2 m x 2 m, yawed 0.3 rad) under it comes
// to rest on its four feet with its base as high above the box's top as it stands above the flat
// ground: the box top is a ground like the other.
double standingHeight(const Robot& r, std::shared_ptr<const Terrain> world, double top) {
  SimOptions opt;
  opt.terrain = std::move(world);
  Simulator sim(r, opt);
  Eigen::VectorXd q = r.default_q;
  q[2] += top + 0.02;
  sim.reset(q, Eigen::VectorXd::Zero(r.model.nv));
  const sim::HoldPolicy hold = sim_test::holdDefault(r);
  Eigen::VectorXd tau(sim.nu());
  double deepest = 0.0;
  for (int i = 0; i < 1500; ++i) {
    hold.torque(r.model, sim.q(), sim.v(), tau);
    EXPECT_EQ(sim.step(tau), StepStatus::Ok) << "step " << i;
    for (const sim::PointContact& c : sim.pointContacts()) deepest = std::min(deepest, c.height);
  }
  EXPECT_GT(deepest, -2e-3);
  for (const sim::PointContact& c : sim.pointContacts()) EXPECT_TRUE(c.in_contact);
  EXPECT_LT(sim.v().lpNorm<Eigen::Infinity>(), 1e-2);
  const double weight = r.model.totalMass() * kG;
  EXPECT_NEAR(sim.totalNormalForce(), weight, 0.01 * weight);
  EXPECT_EQ(sim.counters().trips, 0);
  return sim.q()[2];
}

TEST(TerrainContact, QuadRestsOnABoxTopAtItsStandingHeight) {
  const Robot& r = robot("stride_quad");
  TerrainSpec s;
  s.boxes.push_back({{0.05, -0.02}, {2.0, 2.0}, 0.15, 0.3});
  const double on_flat = standingHeight(r, nullptr, 0.0);
  const double on_box = standingHeight(r, std::make_shared<Terrain>(s), 0.15);
  EXPECT_NEAR(on_box - 0.15, on_flat, 1e-3);
  EXPECT_NEAR(on_box - 0.15, r.default_q[2], 5e-3);  // the joint PD sags a little
  std::cout << "base above the box top " << on_box - 0.15 << " m, above the flat ground " << on_flat
            << " m\n";
}

// ---------------------------------------------------------------------------------------------
// The sled (1 kg, 0.2 m square) set down on a 20° ramp, its bottom on the ramp's plane: with
// μ = 1 > tan 20° it stays put and its corners stay on the plane, the ramp carrying its weight
// straight up; with μ = 0.1 it slides down at g (sin 20° − μ cos 20°), friction μ N up the slope.
struct RampRun {
  double along = 0.0;  // displacement along the slope, uphill positive
  double across = 0.0, lift = 0.0;
  double corner_gap = 0.0;  // the largest |distance| of a corner to the ramp's plane, at the end
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // the sum of the contact forces, last step
  bool all_in_contact = true;
};

RampRun sledOnRamp(double mu, int steps) {
  const double th = 20.0 * kPi / 180.0;
  TerrainSpec s;
  s.ramps.push_back({{-1.0, 0.0}, {3.0, 0.0}, 2.0, 4.0 * std::tan(th)});
  const auto ramp = std::make_shared<Terrain>(s);
  sim_test::Sled sled;
  SimOptions opt;
  opt.terrain = ramp;
  opt.friction = mu;
  Simulator sim(sled.model, sled.points, opt);
  const Eigen::Vector3d n(-std::sin(th), 0.0, std::cos(th)), up(std::cos(th), 0.0, std::sin(th));
  const Eigen::Vector3d centre = Eigen::Vector3d(2.0, 0.0, 3.0 * std::tan(th)) + sled.kHalfZ * n;
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(-th, Eigen::Vector3d::UnitY()));
  Eigen::VectorXd q(7);
  for (int k = 0; k < 3; ++k) q[k] = centre[k];
  for (int k = 0; k < 4; ++k) q[3 + k] = tilt.coeffs()[k];  // x y z w
  sim.reset(q, Eigen::VectorXd::Zero(6));
  const Eigen::VectorXd none(0);
  for (int i = 0; i < steps; ++i) EXPECT_EQ(sim.step(none), StepStatus::Ok) << "step " << i;
  RampRun run;
  const Eigen::Vector3d d = sim.q().head<3>() - centre;
  run.along = d.dot(up);
  run.across = d.y();
  run.lift = d.dot(n);
  const Eigen::Quaterniond now(sim.q()[6], sim.q()[3], sim.q()[4], sim.q()[5]);
  for (size_t i = 0; i < sled.points.size(); ++i) {
    const Eigen::Vector3d p = sim.q().head<3>() + now * sled.points[i].offset;
    const double gap = (p.z() - ramp->height(p.x(), p.y())) * std::cos(th);
    run.corner_gap = std::max(run.corner_gap, std::abs(gap));
    run.all_in_contact &= sim.pointContacts()[i].in_contact;
    run.force += sim.contactForces().col(static_cast<Eigen::Index>(i));
  }
  return run;
}

TEST(TerrainContact, SledStaysOnARampWithEnoughFriction) {
  const RampRun run = sledOnRamp(1.0, 1000);
  const double mg = sim_test::Sled::kMass * kG;
  EXPECT_LT(std::abs(run.along), 1e-2);
  EXPECT_LT(std::abs(run.across), 1e-3);
  EXPECT_LT(std::abs(run.lift), 1e-3);
  EXPECT_LT(run.corner_gap, 1e-3) << "the corners sit on the ramp's plane";
  EXPECT_TRUE(run.all_in_contact);
  EXPECT_NEAR(run.force.x(), 0.0, 1e-2 * mg);
  EXPECT_NEAR(run.force.y(), 0.0, 1e-2 * mg);
  EXPECT_NEAR(run.force.z(), mg, 1e-2 * mg);
  std::cout << "drift along the ramp " << run.along << " m with mu 1\n";
}

TEST(TerrainContact, SledSlidesDownARampWithLittleFriction) {
  const double th = 20.0 * kPi / 180.0, mu = 0.1, t = 1.0;
  const RampRun run = sledOnRamp(mu, 1000);
  const double expected = -0.5 * kG * (std::sin(th) - mu * std::cos(th)) * t * t;
  EXPECT_NEAR(run.along, expected, 0.02 * std::abs(expected));
  EXPECT_LT(std::abs(run.across), 1e-3);
  EXPECT_LT(std::abs(run.lift), 1e-3);
  EXPECT_LT(run.corner_gap, 1e-3);
  EXPECT_TRUE(run.all_in_contact);
  // The normal force m g cos θ along the ramp's normal, friction μ of it up the slope.
  const double mg = sim_test::Sled::kMass * kG, N = mg * std::cos(th);
  const Eigen::Vector3d n(-std::sin(th), 0.0, std::cos(th)), up(std::cos(th), 0.0, std::sin(th));
  EXPECT_NEAR((run.force - N * (n + mu * up)).norm(), 0.0, 1e-2 * mg) << run.force.transpose();
  std::cout << "slid " << run.along << " m along the ramp in 1 s (Coulomb " << expected << ")\n";
}

// ---------------------------------------------------------------------------------------------
// A puck (1 kg, one contact point at its centre of mass: a foot without a leg, no tipping) on the
// ground, swept into a single step 0.1 m high whose riser is 0.2 m ahead: pushed along at 12 N
// (μ m g = 7.8 N), or thrown at 3 m/s. The riser stops it at its plane (never more than 2 mm
// past it), it stays on the ground (it does not climb the riser) and the first touch of the riser
// is one trip. The same sweeps on the flat ground cross the riser's place, with no trip.
struct Puck {
  Model model;
  std::vector<sim::ContactPoint> points;
  Puck() {
    const int j = model.addJoint(0, JointType::FreeFlyer, SE3::Identity(), "root");
    model.appendBodyToJoint(j, Inertia::FromMassComInertia(1.0, Eigen::Vector3d::Zero(),
                                                           Eigen::Matrix3d::Identity() * 1e-3));
    points.push_back({"puck", model.getFrameId("root"), Eigen::Vector3d::Zero(), 0});
  }
};

struct Sweep {
  double max_past = -1.0;  // the largest x past the riser's plane
  double max_z = -1.0;     // the highest the puck got
  double final_x = 0.0;
  std::int64_t trips = 0;
};

constexpr double kRiserX = 0.2;

std::shared_ptr<const Terrain> singleStep() {
  TerrainSpec s;
  terrain::StairsSpec f;
  f.start = {kRiserX, 0.0};
  f.steps = 1;
  f.rise = 0.1;
  f.run = 0.5;
  f.width = 2.0;
  s.stairs.push_back(f);
  return std::make_shared<Terrain>(s);
}

// `push` N along x for 1 s, or thrown at `speed` m/s; 1 s in all. With `allocations`, the
// allocations of the 1000 steps are counted.
Sweep sweepPuck(std::shared_ptr<const Terrain> world, double push, double speed,
                long* allocations = nullptr) {
  const Puck puck;
  SimOptions opt;
  opt.terrain = std::move(world);
  Simulator sim(puck.model, puck.points, opt);
  Eigen::VectorXd q(7);
  q << 0, 0, 0, 0, 0, 0, 1;
  sim.reset(q, Eigen::VectorXd::Zero(6));
  const Eigen::VectorXd none(0);
  for (int i = 0; i < 50; ++i) sim.step(none);  // resting on the ground
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[0] = speed;
  sim.reset(sim.q(), v, sim.time());
  Vector6d wrench = Vector6d::Zero();
  wrench[0] = push;
  sim.applyExternalWrench(wrench, sim.time() + 1.0);
  Sweep sweep;
  auto run = [&] {
    for (int i = 0; i < 1000; ++i) {
      if (sim.step(none) != StepStatus::Ok) ADD_FAILURE() << "step " << i;
      sweep.max_past = std::max(sweep.max_past, sim.q()[0] - kRiserX);
      sweep.max_z = std::max(sweep.max_z, sim.q()[2]);
    }
  };
  if (allocations)
    *allocations = test_support::allocations(run);
  else
    run();
  sweep.final_x = sim.q()[0];
  sweep.trips = sim.counters().trips;
  return sweep;
}

TEST(TerrainContact, PuckSweptIntoARiserIsStoppedAndTripsOnce) {
  struct Case {
    const char* what;
    double push, speed;
  };
  for (const Case& c : {Case{"pushed at 12 N", 12.0, 0.0}, Case{"thrown at 3 m/s", 0.0, 3.0}}) {
    SCOPED_TRACE(c.what);
    const Sweep step = sweepPuck(singleStep(), c.push, c.speed);
    EXPECT_LT(step.max_past, 2e-3) << "got that far into the riser";
    EXPECT_LT(step.max_z, 5e-4) << "lifted off the ground, up the riser";
    EXPECT_LT(step.final_x, kRiserX + 1e-3);
    EXPECT_EQ(step.trips, 1);
    std::cout << c.what << ": deepest into the riser " << step.max_past << " m, highest "
              << step.max_z << " m, trips " << step.trips << "\n";
    for (const std::shared_ptr<const Terrain>& flat :
         {std::shared_ptr<const Terrain>(), std::make_shared<const Terrain>(0.0)}) {
      const Sweep free = sweepPuck(flat, c.push, c.speed);
      EXPECT_GT(free.max_past, 0.1) << "the sweep would have crossed the riser's place";
      EXPECT_EQ(free.trips, 0);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Footholds near edges (SimCounters::footholds, edge_footholds, min_edge_distance). The stairs of
// stride_quad's terrains: 3 steps of 8 cm x 25 cm from x = 0.2 m, 1 m wide; tread 1 (top 0.08 m)
// from its nosing at x = 0.2 to the next riser at x = 0.45.
constexpr double kNosing = 0.2, kRun = 0.25, kRise = 0.08;

std::shared_ptr<const Terrain> stairs() {
  TerrainSpec s;
  terrain::StairsSpec f;
  f.start = {kNosing, 0.0};
  f.steps = 3;
  f.rise = kRise;
  f.run = kRun;
  f.width = 1.0;
  s.stairs.push_back(f);
  return std::make_shared<Terrain>(s);
}

TEST(TerrainContact, EdgeDistanceOnStairsAndRamps) {
  const auto flight = stairs();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* what;
    double x, y, expected;
  };
  const Case cases[] = {
      {"on tread 1, 1 cm from its nosing (the top of a drop)", kNosing + 0.01, 0.0, 0.01},
      {"on the ground, 1 cm before the first riser (the foot of a wall)", kNosing - 0.01, 0.1,
       0.01},
      {"on tread 1, 1 cm before the next riser", kNosing + kRun - 0.01, -0.2, 0.01},
      {"on tread 1, 3 cm from its nosing", kNosing + 0.03, 0.0, 0.03},
      {"mid-tread: 12.5 cm from either edge", kNosing + 0.5 * kRun, 0.0, inf},
      {"on a riser's line", kNosing + kRun, 0.0, 0.0},
      {"beside the flight, 1 cm from its side", kNosing + 0.1, 0.51, 0.01},
      {"beside the flight's corner, 3 cm off it in x and in y", kNosing - 0.03, 0.53,
       std::hypot(0.03, 0.03)},
      {"on the ground far from it", -1.0, 0.0, inf},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const double d = flight->edgeDistance(c.x, c.y, 0.02, 0.05);
    if (std::isinf(c.expected))
      EXPECT_TRUE(std::isinf(d)) << d;
    else
      EXPECT_NEAR(d, c.expected, 1e-9);
  }
  // Only steps of more than min_rise: the 8 cm risers are no edge for 10 cm, and none beyond the
  // radius.
  EXPECT_TRUE(std::isinf(flight->edgeDistance(kNosing + 0.01, 0.0, 0.1, 0.05)));
  EXPECT_TRUE(std::isinf(flight->edgeDistance(kNosing + 0.03, 0.0, 0.02, 0.0299)));
  EXPECT_NEAR(flight->edgeDistance(kNosing + 0.03, 0.0, 0.02, 0.0301), 0.03, 1e-9);
  // Flat ground, and places that are not: no edge.
  EXPECT_TRUE(std::isinf(Terrain(0.1).edgeDistance(0.0, 0.0, 0.02, 0.05)));
  EXPECT_TRUE(std::isinf(flight->edgeDistance(std::nan(""), 0.0, 0.02, 0.05)));
  EXPECT_TRUE(std::isinf(flight->edgeDistance(kNosing, 0.0, 0.02, inf)));

  // A ramp rising 10 cm over 1 m along x from x = 0, 1 m wide: its foot is a kink, not an edge;
  // its high end is a 10 cm drop; its sides are faces whose height grows along them, past 2 cm
  // from x = 0.2 on: a place 1 cm beside the side at x = 0.19 is sqrt(2) cm from that point, one at
  // x = 0.1 has no edge within 5 cm (the side is 1 cm high there).
  TerrainSpec s;
  s.ramps.push_back({{0.0, 0.0}, {1.0, 0.0}, 1.0, 0.1});
  const Terrain ramp(s);
  EXPECT_TRUE(std::isinf(ramp.edgeDistance(-0.01, 0.0, 0.02, 0.05))) << "the foot";
  EXPECT_TRUE(std::isinf(ramp.edgeDistance(0.01, 0.0, 0.02, 0.05))) << "the foot";
  EXPECT_NEAR(ramp.edgeDistance(0.99, 0.0, 0.02, 0.05), 0.01, 1e-9) << "the high end";
  EXPECT_NEAR(ramp.edgeDistance(1.01, 0.0, 0.02, 0.05), 0.01, 1e-9) << "below the high end";
  EXPECT_NEAR(ramp.edgeDistance(0.19, 0.51, 0.02, 0.05), std::sqrt(2.0) * 0.01, 1e-5) << "side";
  EXPECT_NEAR(ramp.edgeDistance(0.19, 0.49, 0.02, 0.05), std::sqrt(2.0) * 0.01, 1e-5) << "side";
  EXPECT_NEAR(ramp.edgeDistance(0.5, 0.51, 0.02, 0.05), 0.01, 1e-9) << "side, 5 cm high";
  EXPECT_TRUE(std::isinf(ramp.edgeDistance(0.1, 0.51, 0.02, 0.05))) << "side, 1 cm high";
}

struct Drop {
  std::int64_t footholds = 0, edge_footholds = 0;
  double min_edge_distance = 0.0;
  double moved = 0.0;  // horizontal drift of the body over the drop
};

// A body of `points` (the puck: one; the sled: four corners) dropped with its lowest points 2 cm
// above the terrain at (x, y), left to rest for 0.5 s.
Drop dropOnto(std::shared_ptr<const Terrain> world, const Model& model,
              const std::vector<sim::ContactPoint>& points, double bottom, double x, double y) {
  SimOptions opt;
  opt.terrain = world;
  Simulator sim(model, points, opt);
  Eigen::VectorXd q(7);
  const double top = world ? world->height(x, y) : 0.0;
  q << x, y, top + 0.02 + bottom, 0, 0, 0, 1;
  sim.reset(q, Eigen::VectorXd::Zero(6));
  const Eigen::VectorXd none(0);
  for (int i = 0; i < 500; ++i) EXPECT_EQ(sim.step(none), StepStatus::Ok) << "step " << i;
  for (const sim::PointContact& c : sim.pointContacts()) EXPECT_TRUE(c.in_contact) << "at rest";
  Drop d;
  d.footholds = sim.counters().footholds;
  d.edge_footholds = sim.counters().edge_footholds;
  d.min_edge_distance = sim.counters().min_edge_distance;
  d.moved = std::hypot(sim.q()[0] - x, sim.q()[1] - y);
  return d;
}

TEST(TerrainContact, AFootDroppedNearAnEdgeIsAnEdgeFoothold) {
  const Puck puck;
  const auto flight = stairs();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* what;
    double x;
    std::int64_t edge;
    double nearest;
  };
  const Case cases[] = {
      {"on tread 1, 1 cm from its nosing", kNosing + 0.01, 1, 0.01},
      {"on the ground, 1 cm before the first riser", kNosing - 0.01, 1, 0.01},
      {"on tread 1, 1 cm before the next riser", kNosing + kRun - 0.01, 1, 0.01},
      {"on tread 1, 3 cm from its nosing", kNosing + 0.03, 0, 0.03},
      {"mid-tread", kNosing + 0.5 * kRun, 0, inf},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const Drop d = dropOnto(flight, puck.model, puck.points, 0.0, c.x, 0.0);
    EXPECT_EQ(d.footholds, 1) << "one touch-down, then resting";
    EXPECT_EQ(d.edge_footholds, c.edge);
    if (std::isinf(c.nearest))
      EXPECT_TRUE(std::isinf(d.min_edge_distance)) << d.min_edge_distance;
    else
      EXPECT_NEAR(d.min_edge_distance, c.nearest, 1e-6);
    EXPECT_LT(d.moved, 1e-6);
  }
  // Flat ground (no terrain, a flat one): never an edge, wherever the foot comes down.
  for (const std::shared_ptr<const Terrain>& flat :
       {std::shared_ptr<const Terrain>(), std::make_shared<const Terrain>(0.0)})
    for (double x : {kNosing - 0.01, kNosing + 0.01, 0.0}) {
      const Drop d = dropOnto(flat, puck.model, puck.points, 0.0, x, 0.0);
      EXPECT_EQ(d.footholds, 1);
      EXPECT_EQ(d.edge_footholds, 0);
      EXPECT_TRUE(std::isinf(d.min_edge_distance));
    }
}

TEST(TerrainContact, ASolesCornersAreFootholdsEach) {
  // The sled (0.2 m square: a sole's four corners) on tread 1, its -x corners 1 cm from the nosing
  // and its +x corners 4 cm before the next riser: four touch-downs, two of them edge footholds.
  const sim_test::Sled sled;
  const double x = kNosing + 0.01 + sled.kHalfX;
  const Drop on_tread = dropOnto(stairs(), sled.model, sled.points, sled.kHalfZ, x, 0.0);
  EXPECT_EQ(on_tread.footholds, 4);
  EXPECT_EQ(on_tread.edge_footholds, 2);
  EXPECT_NEAR(on_tread.min_edge_distance, 0.01, 1e-6);
  const Drop flat = dropOnto(nullptr, sled.model, sled.points, sled.kHalfZ, x, 0.0);
  EXPECT_EQ(flat.footholds, 4);
  EXPECT_EQ(flat.edge_footholds, 0);
  EXPECT_TRUE(std::isinf(flat.min_edge_distance));
}

TEST(TerrainContact, AFootholdIsATouchDownAfterASwing) {
  // The puck at rest on tread 1, 1 cm from its nosing (one edge foothold), lifted by an upward
  // force on its body: a hop of 9 mm comes down where it was and is no new foothold, one of 10 cm
  // (above foothold_lift, 2 cm) is.
  const Puck puck;
  SimOptions opt;
  opt.terrain = stairs();
  Simulator sim(puck.model, puck.points, opt);
  Eigen::VectorXd q(7);
  q << kNosing + 0.01, 0, kRise + 0.005, 0, 0, 0, 1;
  sim.reset(q, Eigen::VectorXd::Zero(6));
  const Eigen::VectorXd none(0);
  auto hop = [&](double force, double duration) {
    Vector6d up = Vector6d::Zero();
    up[2] = force * kG;  // the puck weighs 1 kg
    sim.applyExternalWrench(up, sim.time() + duration);
    double apex = 0.0;
    for (int i = 0; i < 800; ++i) {
      EXPECT_EQ(sim.step(none), StepStatus::Ok);
      apex = std::max(apex, sim.q()[2] - kRise);
    }
    EXPECT_TRUE(sim.pointContacts()[0].in_contact) << "landed";
    return apex;
  };
  for (int i = 0; i < 300; ++i) sim.step(none);
  EXPECT_EQ(sim.counters().footholds, 1);
  EXPECT_EQ(sim.counters().edge_footholds, 1);
  const double low = hop(1.5, 0.05);
  EXPECT_GT(low, 0.005);
  EXPECT_LT(low, 0.015);
  EXPECT_EQ(sim.counters().footholds, 1) << "a hop of " << low << " m";
  const double high = hop(2.0, 0.1);
  EXPECT_GT(high, 0.05);
  EXPECT_EQ(sim.counters().footholds, 2) << "a hop of " << high << " m";
  EXPECT_EQ(sim.counters().edge_footholds, 2);
  EXPECT_NEAR(sim.counters().min_edge_distance, 0.01, 1e-6);
}

TEST(TerrainContact, TheQuadStandingOnFlatGroundHasNoEdgeFootholds) {
  // Dropped from 2 cm and held, on the flat ground and on a box top 2 m wide: each of the four
  // feet touches down once (the front feet bounce ~1 cm on the PD legs after landing: below
  // foothold_lift, no new footholds), and no edge is near any foot.
  const Robot& r = robot("stride_quad");
  TerrainSpec box;
  box.boxes.push_back({{0.0, 0.0}, {2.0, 2.0}, 0.15, 0.0});
  for (const std::shared_ptr<const Terrain>& world :
       {std::shared_ptr<const Terrain>(), std::make_shared<const Terrain>(box)}) {
    SimOptions opt;
    opt.terrain = world;
    Simulator sim(r, opt);
    Eigen::VectorXd q = r.default_q;
    q[2] += 0.02 + (world ? 0.15 : 0.0);
    sim.reset(q, Eigen::VectorXd::Zero(r.model.nv));
    const sim::HoldPolicy hold = sim_test::holdDefault(r);
    Eigen::VectorXd tau(sim.nu());
    for (int i = 0; i < 1000; ++i) {
      hold.torque(r.model, sim.q(), sim.v(), tau);
      sim.step(tau);
    }
    EXPECT_EQ(sim.counters().footholds, 4);
    EXPECT_EQ(sim.counters().edge_footholds, 0);
    EXPECT_TRUE(std::isinf(sim.counters().min_edge_distance));
  }
}

TEST(TerrainContact, SolesFlatOnTheGroundNotSetLevelOnARamp) {
  // stride_humanoid dropped 1 cm and held: on flat ground its soles stand flat (every corner within
  // 5 mm of the ground); set down level on a 10° ramp, one end of each sole is 3.5 cm above it,
  // and they are not. The quadruped has no soles: no such steps.
  const Robot& h = robot("stride_humanoid");
  const double slope = std::tan(10.0 * kPi / 180.0);
  TerrainSpec ramp;
  ramp.ramps.push_back({{-2.0, 0.0}, {2.0, 0.0}, 4.0, 4.0 * slope});
  auto fraction = [&](const std::shared_ptr<const Terrain>& world, double lift) {
    SimOptions opt;
    opt.terrain = world;
    Simulator sim(h, opt);
    Eigen::VectorXd q = h.default_q;
    q[2] += 0.01 + lift;
    sim.reset(q, Eigen::VectorXd::Zero(h.model.nv));
    const sim::HoldPolicy hold = sim_test::holdDefault(h);
    Eigen::VectorXd tau(sim.nu());
    for (int i = 0; i < 300; ++i) {
      hold.torque(h.model, sim.q(), sim.v(), tau);
      sim.step(tau);
    }
    EXPECT_GT(sim.counters().sole_steps, 200);  // two soles, down after ~0.05 s
    return sim::soleFlatFraction(sim.counters());
  };
  EXPECT_GT(fraction(nullptr, 0.0), 0.95);
  // Its soles' highest point over the ramp's middle: 2 x 0.1 x tan(10°) / 2 above the centre.
  EXPECT_LT(fraction(std::make_shared<const Terrain>(ramp), 2.0 * slope + 0.1 * slope), 0.05);
  const Robot& quad = robot("stride_quad");
  Simulator sim(quad, SimOptions{});
  sim.reset(quad.default_q, Eigen::VectorXd::Zero(quad.model.nv));
  for (int i = 0; i < 100; ++i) sim.step(Eigen::VectorXd::Zero(sim.nu()));
  EXPECT_EQ(sim.counters().sole_steps, 0);
  EXPECT_TRUE(std::isnan(sim::soleFlatFraction(sim.counters())));
}

// ---------------------------------------------------------------------------------------------
// step() allocates nothing with walls in play: the puck's sweep into the riser, and the quadruped
// dropped from 5 cm onto a rough patch (5 cm cells, ±2 cm) in front of a flight (1 and 3
// substeps).
TEST(TerrainContact, StepAllocatesNothingOnStairsAndRoughGround) {
  long n = -1;
  const Sweep sweep = sweepPuck(singleStep(), 12.0, 0.0, &n);
  EXPECT_EQ(n, 0) << "the puck's sweep into the riser";
  EXPECT_GE(sweep.trips, 1) << "the riser was touched";

  TerrainSpec s;
  s.rough.push_back({{-1.0, -1.0}, {1.0, 1.0}, 0.05, 0.02, 5});
  terrain::StairsSpec f;
  f.start = {0.3, 0.0};
  f.steps = 3;
  f.rise = 0.08;
  f.run = 0.25;
  f.width = 1.0;
  s.stairs.push_back(f);
  const Robot& r = robot("stride_quad");
  for (int substeps : {1, 3}) {
    SimOptions opt;
    opt.substeps = substeps;
    opt.terrain = std::make_shared<Terrain>(s);
    Simulator sim(r, opt);
    Eigen::VectorXd q = r.default_q;
    q[2] += 0.05;
    sim.reset(q, Eigen::VectorXd::Zero(r.model.nv));
    const sim::HoldPolicy hold = sim_test::holdDefault(r);
    Eigen::VectorXd tau(sim.nu());
    double most_force = 0.0;
    const long allocations = test_support::allocations([&] {
      for (int i = 0; i < 600; ++i) {
        hold.torque(r.model, sim.q(), sim.v(), tau);
        sim.step(tau);
        most_force = std::max(most_force, sim.totalNormalForce());
      }
    });
    EXPECT_EQ(allocations, 0) << "substeps " << substeps;
    EXPECT_GT(most_force, 0.0) << "it landed";
    EXPECT_GE(sim.counters().footholds, 4) << "the touch-downs' edge distances were measured";
  }
}

}  // namespace test_terrain_contact
}  // namespace stride
