#include "tools/bench/robots.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <random>

#include "config/robot_config.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride::bench {

namespace {
BenchRobot withSamples(std::string name, Model model) {
  BenchRobot r{std::move(name), std::move(model), {}, {}, {}, {}};
  std::mt19937 rng(42);
  for (int k = 0; k < kBatch; ++k) {
    r.q.push_back(randomConfiguration(r.model, rng));
    r.v.push_back(Eigen::VectorXd::Random(r.model.nv));
    r.a.push_back(Eigen::VectorXd::Random(r.model.nv));
    r.tau.push_back(Eigen::VectorXd::Random(r.model.nv));
  }
  return r;
}
std::filesystem::path sharedDir() {
  const char* env = std::getenv("STRIDE_SHARED_DIR");
  return env ? env : STRIDE_SHARED_DIR;
}
}  // namespace

const BenchRobot* solo8Robot() {
  static const std::optional<BenchRobot> robot = []() -> std::optional<BenchRobot> {
    const auto path = sharedDir() / "robots/solo12/solo.urdf";
    if (!std::filesystem::exists(path)) {
      std::cerr << "note: " << path << " not found, solo8 is not benchmarked\n";
      return std::nullopt;
    }
    return withSamples("solo8", buildModelFromUrdf(path.string(), RootJoint::FreeFlyer));
  }();
  return robot ? &*robot : nullptr;
}

const std::vector<BenchRobot>& benchRobots() {
  static const std::vector<BenchRobot> robots = [] {
    std::vector<BenchRobot> out;
    const std::filesystem::path shared = sharedDir();
    const struct {
      const char* name;
      const char* urdf;
      RootJoint root;
    } shared_robots[] = {{"solo12", "robots/solo12/solo12.urdf", RootJoint::FreeFlyer},
                         {"talos_reduced", "robots/talos/talos_reduced.urdf", RootJoint::FreeFlyer},
                         {"ur5", "robots/ur5/ur5_robot.urdf", RootJoint::Fixed}};
    for (const auto& s : shared_robots) {
      const auto path = shared / s.urdf;
      if (!std::filesystem::exists(path)) {
        std::cerr << "note: " << path << " not found, " << s.name << " is not benchmarked\n";
        continue;
      }
      out.push_back(withSamples(s.name, buildModelFromUrdf(path.string(), s.root)));
    }
    for (const char* name : {"stride_quad", "stride_humanoid"}) {
      const std::string yaml =
          std::string(STRIDE_CONFIG_DIR) + "/robots/" + name + "/" + name + ".yaml";
      out.push_back(withSamples(name, loadRobot(yaml).model));
    }
    return out;
  }();
  return robots;
}

}  // namespace stride::bench
