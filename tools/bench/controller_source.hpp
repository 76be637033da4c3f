#pragma once
// The controller configuration a controller benchmark runs on (controller_tick, tick_parts,
// reference_update): a shipped one, config/controller/NAME.yaml, or any file given to stride-bench
// (--config FILE or STRIDE_BENCH_CONFIG=FILE), whose paths are relative to its folder as
// stride-mpc reads them. The file is only read.

#include <string>
#include <utility>
#include <vector>

#include "controller/controller_config.hpp"

namespace stride::bench {

struct ControllerSource {
  std::string path;
  std::vector<std::string> robots_dirs;  // looked in before build/robot_packages
};

inline ControllerSource shippedController(const std::string& name) {
  return {std::string(STRIDE_CONFIG_DIR) + "/controller/" + name + ".yaml", {}};
}

// The configuration, its public robots looked for in the source's folders, then in the build's
// package view of ../shared (build/robot_packages).
inline ControllerConfig loadController(const ControllerSource& source) {
  ControllerConfig c = loadControllerConfig(source.path);
  c.robots_dirs = source.robots_dirs;
  c.robots_dirs.push_back(STRIDE_ROBOT_PACKAGES);
  return c;
}

// Registered by main() for stride-bench --config FILE: controller_tick/NAME, tick_parts/NAME/
// {derivatives,backward,forward} (bench_controller.cpp) and reference_update/NAME
// (bench_reference.cpp) on that configuration.
void registerControllerBenchmarks(const ControllerSource& source, const std::string& name,
                                  const ControllerConfig& config);
void registerReferenceBenchmark(const ControllerSource& source, const std::string& name,
                                const ControllerConfig& config);

}  // namespace stride::bench
