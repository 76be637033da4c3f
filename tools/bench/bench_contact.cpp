// Derivatives, contact dynamics and the knot of eq. 11: <algorithm>/<robot>, on solo12 with its 4
// point feet and talos_reduced with its 2 soles (forces LOCAL, as the reference files).

#include <benchmark/benchmark.h>

#include <functional>

#include "solver/contact/knot_dynamics.hpp"
#include "solver/multibody/aba_derivatives.hpp"
#include "solver/multibody/rnea_derivatives.hpp"
#include "tools/bench/robots.hpp"

namespace stride::bench {
namespace {

struct ContactRobot {
  const BenchRobot* robot;
  ContactSet contacts;
};

std::vector<ContactRobot>& contactRobots() {
  static std::vector<ContactRobot> out = [] {
    std::vector<ContactRobot> r;
    for (const BenchRobot& b : benchRobots()) {
      ContactSet c;
      if (b.name == "solo12") {
        for (const char* f : {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"}) c.add(b.model, f, 3);
      } else if (b.name == "talos_reduced") {
        for (const char* f : {"left_sole_link", "right_sole_link"}) c.add(b.model, f, 6);
      } else {
        continue;
      }
      r.push_back({&b, std::move(c)});
    }
    return r;
  }();
  return out;
}

using Kernel = std::function<void(const BenchRobot&, const ContactSet&, Data&, KnotData&, int)>;

void registerKernel(const std::string& algorithm, const Kernel& kernel) {
  for (const ContactRobot& cr : contactRobots()) {
    benchmark::RegisterBenchmark((algorithm + "/" + cr.robot->name).c_str(),
                                 [&cr, kernel](benchmark::State& state) {
                                   Data data(cr.robot->model);
                                   KnotData kd(cr.robot->model, cr.contacts);
                                   int k = 0;
                                   for (auto _ : state) {
                                     kernel(*cr.robot, cr.contacts, data, kd, k);
                                     benchmark::ClobberMemory();
                                     k = (k + 1) % kBatch;
                                   }
                                 })
        ->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace

void registerContactBenchmarks() {
  registerKernel("rnea_derivatives",
                 [](const BenchRobot& r, const ContactSet&, Data& d, KnotData&, int k) {
                   computeRNEADerivatives(r.model, d, r.q[k], r.v[k], r.a[k]);
                 });
  registerKernel("aba_derivatives",
                 [](const BenchRobot& r, const ContactSet&, Data& d, KnotData&, int k) {
                   computeABADerivatives(r.model, d, r.q[k], r.v[k], r.tau[k]);
                 });
  registerKernel("contact_dynamics",
                 [](const BenchRobot& r, const ContactSet& c, Data& d, KnotData& kd, int k) {
                   contactDynamics(r.model, d, c, kd.contact, r.q[k], r.v[k], r.tau[k]);
                 });
  registerKernel("contact_dynamics_derivatives",
                 [](const BenchRobot& r, const ContactSet& c, Data& d, KnotData& kd, int k) {
                   contactDynamicsDerivatives(r.model, d, c, kd.contact, r.q[k], r.v[k], r.tau[k]);
                 });
  registerKernel("impulse_dynamics_derivatives",
                 [](const BenchRobot& r, const ContactSet& c, Data& d, KnotData& kd, int k) {
                   impulseDynamicsDerivatives(r.model, d, c, kd.contact, r.q[k], r.v[k]);
                 });
  // The full knot: KKT dynamics, Euler step, Fx, Fu, Gx, Gu (dt = 10 ms).
  registerKernel(
      "knot", [](const BenchRobot& r, const ContactSet& c, Data& d, KnotData& kd, int k) {
        knotDynamicsDerivatives(r.model, d, c, kd, r.q[k], r.v[k], r.tau[k].tail(kd.nu), 0.01);
      });
}

}  // namespace stride::bench
