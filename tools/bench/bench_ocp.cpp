// The optimal-control benchmarks. knots/<robot>/{calc,calcDiff,backward,forward}/<threads>: the
// four parts of one DDP iteration on a fixed problem the field already benchmarks (so figures
// compare one to one): 100 knots of KKT contact dynamics with an Euler step of 5 ms, contacts with
// Baumgarte gains (kp 0, kd 50) and LOCAL_WORLD_ALIGNED forces, the robot at its SRDF posture
// with zero velocity and zero controls; running cost = placement of an end-effector frame to
// (identity, (0, 0, 0.4)) with weight 1 plus state and control regularization with weight 1e-4;
// terminal cost = the same placement.
// fddp_iteration/solo12_steps/<threads>: one full FDDP iteration with its line search on the
// solver's own fixture (tests/ocp/shooting_cases.hpp: solo12 stepping, built from solver/ocp types
// alone); the locomotion problems' are bench_locomotion.cpp's.

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "solver/ddp/solver.hpp"
#include "solver/multibody/srdf.hpp"
#include "solver/multibody/urdf.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"
#include "tests/ocp/shooting_cases.hpp"

namespace stride::bench {
namespace {

struct KnotsSpec {
  const char* name;
  const char* urdf;
  const char* srdf;
  const char* posture;
  std::vector<const char*> contacts;
  int dim;
  const char* end_effector;
};

const std::vector<KnotsSpec>& specs() {
  static const std::vector<KnotsSpec> s = {
      {"solo",
       "robots/solo12/solo.urdf",
       "robots/solo12/solo.srdf",
       "standing",
       {"FR_KFE", "HL_KFE"},
       3,
       "HL_KFE"},
      {"anymal",
       "robots/anymal/anymal.urdf",
       "robots/anymal/anymal.srdf",
       "standing",
       {"RF_KFE", "LF_KFE", "LH_KFE"},
       3,
       "RH_KFE"},
      {"hyq",
       "robots/hyq/hyq_no_sensors.urdf",
       "robots/hyq/hyq.srdf",
       "standing",
       {"rf_kfe_joint", "lf_kfe_joint", "lh_kfe_joint"},
       3,
       "rh_kfe_joint"},
      {"talos",
       "robots/talos/talos_reduced.urdf",
       "robots/talos/talos.srdf",
       "half_sitting",
       {"leg_right_6_joint", "leg_left_6_joint"},
       6,
       "arm_right_7_joint"},
  };
  return s;
}

struct KnotsProblem {
  Model model;
  std::unique_ptr<ShootingProblem> problem;
  std::unique_ptr<Solver> solver;
};

std::unique_ptr<KnotsProblem> buildKnots(const KnotsSpec& spec) {
  const char* env = std::getenv("STRIDE_SHARED_DIR");
  const std::filesystem::path shared = env ? env : STRIDE_SHARED_DIR;
  if (!std::filesystem::exists(shared / spec.urdf)) {
    std::cerr << "note: " << (shared / spec.urdf) << " not found, knots/" << spec.name
              << " is not benchmarked\n";
    return nullptr;
  }
  auto kp = std::make_unique<KnotsProblem>();
  kp->model = buildModelFromUrdf((shared / spec.urdf).string(), RootJoint::FreeFlyer);
  loadReferenceConfigurations(kp->model, (shared / spec.srdf).string());
  const Model& model = kp->model;
  const int nu = model.nv - 6;
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(model.nq + model.nv);
  x0.head(model.nq) = model.referenceConfigurations.at(spec.posture);
  ContactSet contacts;
  for (const char* c : spec.contacts)
    contacts.add(model, c, spec.dim, ReferenceFrame::LocalWorldAligned, 0.0, 50.0);
  const SE3 target(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 0.4));
  std::vector<std::unique_ptr<ActionModel>> running;
  auto workspace = std::make_shared<SharedWorkspace>(model, 2);
  for (int k = 0; k < 100; ++k) {
    auto knot = std::make_unique<KnotModel>(model, contacts, 5e-3, workspace);
    CostModel& costs = knot->costs();
    costs.add("placement",
              std::make_unique<FramePlacementResidual>(model, nu, spec.end_effector, target),
              Activation::quadratic(6), 1.0);
    costs.add("state", std::make_unique<StateResidual>(model, nu, x0),
              Activation::quadratic(2 * model.nv), 1e-4);
    costs.add("control", std::make_unique<ControlResidual>(model, nu), Activation::quadratic(nu),
              1e-4);
    running.push_back(std::move(knot));
  }
  auto terminal = std::make_unique<TerminalModel>(model);
  terminal->costs().add(
      "placement", std::make_unique<FramePlacementResidual>(model, 0, spec.end_effector, target),
      Activation::quadratic(6), 1.0);
  kp->problem = std::make_unique<ShootingProblem>(x0, std::move(running), std::move(terminal));
  kp->solver = std::make_unique<Solver>(*kp->problem, SolverKind::Fddp);
  return kp;
}

KnotsProblem* knotsProblem(const KnotsSpec& spec) {
  static std::map<std::string, std::unique_ptr<KnotsProblem>> cache;
  auto it = cache.find(spec.name);
  if (it == cache.end()) it = cache.emplace(spec.name, buildKnots(spec)).first;
  return it->second.get();
}

enum class Part { Calc, CalcDiff, Backward, Forward };

void runPart(benchmark::State& state, const KnotsSpec& spec, Part part) {
  KnotsProblem* kp = knotsProblem(spec);
  if (!kp) {
    state.SkipWithError("robot files not found");
    return;
  }
  kp->problem->setThreads(static_cast<int>(state.range(0)));
  Solver& solver = *kp->solver;
  // The warm start of the field's benchmark: x0 everywhere, zero controls.
  solver.computeDerivatives();
  solver.backwardPass();
  // The forward pass is timed at the longest step whose rollout succeeds (on talos the full step
  // drives a knot into a singular contact configuration, and a failed rollout stops early).
  double alpha = 1.0;
  while (alpha > 1e-3 && !std::isfinite(solver.forwardPass(alpha))) alpha *= 0.5;
  state.counters["alpha"] = alpha;
  // In a DDP iteration calcDiff runs at the point of the accepted rollout, whose calc has just
  // solved each knot's contact dynamics there; the knots keep that solve (KeptSolve in
  // solver/ocp/knot.hpp), as the field's libraries keep calc's results for calcDiff.
  if (part == Part::CalcDiff) kp->problem->calc(solver.xs(), solver.us());
  for (auto _ : state) {
    switch (part) {
      case Part::Calc:
        benchmark::DoNotOptimize(kp->problem->calc(solver.xs(), solver.us()));
        break;
      case Part::CalcDiff:
        benchmark::DoNotOptimize(kp->problem->calcDiff(solver.xs(), solver.us()));
        break;
      case Part::Backward:
        benchmark::DoNotOptimize(solver.backwardPass());
        break;
      case Part::Forward:
        benchmark::DoNotOptimize(solver.forwardPass(alpha));
        break;
    }
  }
}

// fddp_iteration/solo12_steps/<threads>: solver.solve(1) from the fixture's standing warm start,
// restored (trajectory and regularization) outside the timing before every iteration, so each
// timed iteration does the same work: calcDiff, backward pass, line search.
void fddpIteration(benchmark::State& state) {
  const char* env = std::getenv("STRIDE_SHARED_DIR");
  const std::string shared = env ? env : STRIDE_SHARED_DIR;
  auto p = shooting_cases::solo12Steps(shared);
  p->problem->setThreads(static_cast<int>(state.range(0)));
  Solver solver(*p->problem, SolverKind::Fddp);
  const double reg = solver.regularization();
  for (auto _ : state) {
    state.PauseTiming();
    solver.setWarmStart(p->xs, p->us);
    solver.setRegularization(reg);
    state.ResumeTiming();
    solver.solve(1);
  }
  state.counters["step"] = solver.stats()[0].step;
}

const bool registered = [] {
  const std::pair<const char*, Part> parts[] = {{"calc", Part::Calc},
                                                {"calcDiff", Part::CalcDiff},
                                                {"backward", Part::Backward},
                                                {"forward", Part::Forward}};
  for (const KnotsSpec& spec : specs())
    for (const auto& [name, part] : parts)
      benchmark::RegisterBenchmark(
          (std::string("knots/") + spec.name + "/" + name).c_str(),
          [&spec, part = part](benchmark::State& s) { runPart(s, spec, part); })
          ->Arg(1)
          ->Arg(2)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
  benchmark::RegisterBenchmark("fddp_iteration/solo12_steps", fddpIteration)
      ->Arg(1)
      ->Arg(2)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  return true;
}();

}  // namespace
}  // namespace stride::bench
