// The locomotion problem's benchmarks. fddp_iteration/<problem>/<threads>: one full FDDP
// iteration with its line search on the locomotion problems of the tests
// (tests/locomotion/locomotion_cases.hpp: solo12_trot, talos_walk). The solver's own iteration,
// on a problem built from solver/ocp alone, is fddp_iteration/solo12_steps (bench_ocp.cpp).

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "solver/ddp/solver.hpp"
#include "tests/locomotion/locomotion_cases.hpp"

namespace stride::bench {
namespace {

// solver.solve(1) from the problem's standing warm start, restored (trajectory and
// regularization) outside the timing before every iteration, so each timed iteration does the
// same work: calcDiff, backward pass, line search.
void fddpIteration(benchmark::State& state, loco_cases::Problem which) {
  const char* env = std::getenv("STRIDE_SHARED_DIR");
  const std::string shared = env ? env : STRIDE_SHARED_DIR;
  loco_cases::Case c = loco_cases::make(which, shared);
  c.loco->problem().setThreads(static_cast<int>(state.range(0)));
  Solver solver(c.loco->problem(), SolverKind::Fddp);
  std::vector<Eigen::VectorXd> xs, us;
  c.warmStart(xs, us);
  const double reg = solver.regularization();
  for (auto _ : state) {
    state.PauseTiming();
    solver.setWarmStart(xs, us);
    solver.setRegularization(reg);
    state.ResumeTiming();
    solver.solve(1);
  }
  state.counters["step"] = solver.stats()[0].step;
}

const bool registered = [] {
  for (loco_cases::Problem p : {loco_cases::Problem::SoloTrot, loco_cases::Problem::TalosStep})
    benchmark::RegisterBenchmark((std::string("fddp_iteration/") + loco_cases::name(p)).c_str(),
                                 [p](benchmark::State& s) { fddpIteration(s, p); })
        ->Arg(1)
        ->Arg(2)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  return true;
}();

}  // namespace
}  // namespace stride::bench
