// Derivatives, contact dynamics and the knot of eq. 11: <algorithm>/<robot>, on solo12 with its 4
// point feet and talos_reduced with its 2 soles (forces LOCAL, as the reference files).

#include <benchmark/benchmark.h>

#include <functional>

#include "solver/contact/knot_dynamics.hpp"
#include "solver/contact/knot_rk4.hpp"
#include "solver/multibody/aba_derivatives.hpp"
#include "solver/multibody/rnea_derivatives.hpp"
#include "tools/bench/robots.hpp"

namespace stride::bench {
namespace {

struct ContactRobot {
  std::string name;  // <algorithm>/<name>
  const BenchRobot* robot;
  ContactSet contacts;
  double dt;  // knot time step
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
        // The DDP benchmark's humanoid problem: ankle contacts, world-aligned forces, velocity
        // Baumgarte term, dt = 5 ms.
        ContactSet c2;
        for (const char* f : {"leg_right_6_joint", "leg_left_6_joint"})
          c2.add(b.model, f, 6, ReferenceFrame::LocalWorldAligned, 0.0, 50.0);
        r.push_back({"talos_2c", &b, std::move(c2), 0.005});
      } else {
        continue;
      }
      r.push_back({b.name, &b, std::move(c), 0.01});
    }
    // The DDP benchmark's quadruped problem: solo8 with two point contacts (FR and HL knees),
    // world-aligned forces, velocity Baumgarte term, dt = 5 ms.
    if (const BenchRobot* solo8 = solo8Robot()) {
      ContactSet c;
      for (const char* f : {"FR_KFE", "HL_KFE"})
        c.add(solo8->model, f, 3, ReferenceFrame::LocalWorldAligned, 0.0, 50.0);
      r.push_back({"solo8_2c", solo8, std::move(c), 0.005});
    }
    return r;
  }();
  return out;
}

using Kernel = std::function<void(const ContactRobot&, Data&, KnotData&, int)>;

// Contact-free kernels run once per robot, not once per contact set.
void registerKernel(const std::string& algorithm, const Kernel& kernel, bool uses_contacts = true) {
  for (const ContactRobot& cr : contactRobots()) {
    if (!uses_contacts && cr.name != cr.robot->name) continue;
    benchmark::RegisterBenchmark((algorithm + "/" + cr.name).c_str(), [&cr, kernel](
                                                                          benchmark::State& state) {
      Data data(cr.robot->model);
      KnotData kd(cr.robot->model, cr.contacts);
      int k = 0;
      for (auto _ : state) {
        kernel(cr, data, kd, k);
        benchmark::ClobberMemory();
        k = (k + 1) % kBatch;
      }
    })->Unit(benchmark::kMicrosecond);
  }
}

// The same knots by Runge-Kutta-Munthe-Kaas 4 (knot_rk4.hpp): four KKT solves per knot, and their
// derivatives chained through the stages.
void registerRk4Knot(const std::string& algorithm, bool derivatives) {
  for (const ContactRobot& cr : contactRobots())
    benchmark::RegisterBenchmark((algorithm + "/" + cr.name).c_str(), [&cr, derivatives](
                                                                          benchmark::State& state) {
      const BenchRobot& r = *cr.robot;
      Data data(r.model);
      Rk4Data rd(r.model, cr.contacts);
      int k = 0;
      for (auto _ : state) {
        const auto u = r.tau[k].tail(rd.nu);
        if (derivatives)
          knotDynamicsRk4Derivatives(r.model, data, cr.contacts, rd, r.q[k], r.v[k], u, cr.dt);
        else
          knotDynamicsRk4(r.model, data, cr.contacts, rd, r.q[k], r.v[k], u, cr.dt);
        benchmark::ClobberMemory();
        k = (k + 1) % kBatch;
      }
    })->Unit(benchmark::kMicrosecond);
}

}  // namespace

void registerContactBenchmarks() {
  registerKernel(
      "rnea_derivatives",
      [](const ContactRobot& c, Data& d, KnotData&, int k) {
        const BenchRobot& r = *c.robot;
        computeRNEADerivatives(r.model, d, r.q[k], r.v[k], r.a[k]);
      },
      false);
  registerKernel(
      "aba_derivatives",
      [](const ContactRobot& c, Data& d, KnotData&, int k) {
        const BenchRobot& r = *c.robot;
        computeABADerivatives(r.model, d, r.q[k], r.v[k], r.tau[k]);
      },
      false);
  registerKernel("contact_dynamics", [](const ContactRobot& c, Data& d, KnotData& kd, int k) {
    const BenchRobot& r = *c.robot;
    contactDynamics(r.model, d, c.contacts, kd.contact, r.q[k], r.v[k], r.tau[k]);
  });
  registerKernel(
      "contact_dynamics_derivatives", [](const ContactRobot& c, Data& d, KnotData& kd, int k) {
        const BenchRobot& r = *c.robot;
        contactDynamicsDerivatives(r.model, d, c.contacts, kd.contact, r.q[k], r.v[k], r.tau[k]);
      });
  registerKernel("impulse_dynamics_derivatives",
                 [](const ContactRobot& c, Data& d, KnotData& kd, int k) {
                   const BenchRobot& r = *c.robot;
                   impulseDynamicsDerivatives(r.model, d, c.contacts, kd.contact, r.q[k], r.v[k]);
                 });
  // The full knot: KKT dynamics, Euler step, Fx, Fu, Gx, Gu (dt = 10 ms, 5 ms for the DDP
  // benchmark's problems).
  registerKernel("knot", [](const ContactRobot& c, Data& d, KnotData& kd, int k) {
    const BenchRobot& r = *c.robot;
    knotDynamicsDerivatives(r.model, d, c.contacts, kd, r.q[k], r.v[k], r.tau[k].tail(kd.nu), c.dt);
  });
  // The knot without derivatives (the DDP forward pass).
  registerKernel("knot_calc", [](const ContactRobot& c, Data& d, KnotData& kd, int k) {
    const BenchRobot& r = *c.robot;
    knotDynamics(r.model, d, c.contacts, kd, r.q[k], r.v[k], r.tau[k].tail(kd.nu), c.dt);
  });
  registerRk4Knot("knot_rk4", true);
  registerRk4Knot("knot_rk4_calc", false);
}

}  // namespace stride::bench
