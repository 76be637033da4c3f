// Multibody algorithms, one benchmark per <algorithm>/<robot>.

#include <benchmark/benchmark.h>

#include <functional>

#include "solver/multibody/aba.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/rnea.hpp"
#include "tools/bench/robots.hpp"

namespace stride::bench {
namespace {

using Kernel = std::function<void(const BenchRobot&, Data&, int sample)>;

void registerAlgorithm(const std::string& algorithm, const Kernel& kernel) {
  for (const BenchRobot& robot : benchRobots()) {
    benchmark::RegisterBenchmark((algorithm + "/" + robot.name).c_str(),
                                 [&robot, kernel](benchmark::State& state) {
                                   Data data(robot.model);
                                   int k = 0;
                                   for (auto _ : state) {
                                     kernel(robot, data, k);
                                     benchmark::ClobberMemory();
                                     k = (k + 1) % kBatch;
                                   }
                                 })
        ->Unit(benchmark::kMicrosecond);
  }
}

// Registered before main runs the benchmarks (tools/bench/main.cpp calls it).
}  // namespace

void registerMultibodyBenchmarks() {
  registerAlgorithm(
      "fk", [](const BenchRobot& r, Data& d, int k) { forwardKinematics(r.model, d, r.q[k]); });
  registerAlgorithm("fk_va", [](const BenchRobot& r, Data& d, int k) {
    forwardKinematics(r.model, d, r.q[k], r.v[k], r.a[k]);
  });
  registerAlgorithm("rnea", [](const BenchRobot& r, Data& d, int k) {
    rnea(r.model, d, r.q[k], r.v[k], r.a[k]);
  });
  registerAlgorithm("nle", [](const BenchRobot& r, Data& d, int k) {
    nonLinearEffects(r.model, d, r.q[k], r.v[k]);
  });
  registerAlgorithm("crba", [](const BenchRobot& r, Data& d, int k) { crba(r.model, d, r.q[k]); });
  registerAlgorithm("aba", [](const BenchRobot& r, Data& d, int k) {
    aba(r.model, d, r.q[k], r.v[k], r.tau[k]);
  });
  registerAlgorithm("jacobians", [](const BenchRobot& r, Data& d, int k) {
    computeJointJacobians(r.model, d, r.q[k]);
  });
  registerAlgorithm("com",
                    [](const BenchRobot& r, Data& d, int k) { centerOfMass(r.model, d, r.q[k]); });
  registerAlgorithm("jacobian_com", [](const BenchRobot& r, Data& d, int k) {
    jacobianCenterOfMass(r.model, d, r.q[k]);
  });
  registerAlgorithm("centroidal_map", [](const BenchRobot& r, Data& d, int k) {
    computeCentroidalMap(r.model, d, r.q[k]);
  });
}

}  // namespace stride::bench
