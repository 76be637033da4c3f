#pragma once
// The robots the benchmarks run on, with a batch of random inputs per robot: benchmark loops cycle
// through the batch so that branch predictors and caches do not see the same input every time.

#include <string>
#include <vector>

#include "solver/multibody/model.hpp"

namespace stride::bench {

struct BenchRobot {
  std::string name;
  Model model;
  std::vector<Eigen::VectorXd> q, v, a, tau;  // kBatch random samples each
};

constexpr int kBatch = 64;

// solo12, talos_reduced, ur5 from the shared robots folder (STRIDE_SHARED_DIR at run time, else
// the path configured at build time; skipped with a note when absent), and the in-house robots.
const std::vector<BenchRobot>& benchRobots();
// solo8 (solo.urdf), for the contact benchmarks only; null when the shared folder lacks it.
const BenchRobot* solo8Robot();

}  // namespace stride::bench
