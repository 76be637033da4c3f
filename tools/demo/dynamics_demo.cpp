// stride-dynamics-demo: what Stride's dynamics core knows about the in-house robots, and how fast
// it computes it. (The closed-loop demo replaces this once the controller exists.)
//   stride-dynamics-demo [--config-dir DIR] [--iterations N]

#include <CLI/CLI.hpp>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include "config/command_line.hpp"
#include "config/robot_config.hpp"
#include "solver/multibody/aba.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"

using namespace stride;

namespace {

// Median over batches of the time of one call, in microseconds.
double medianMicroseconds(const std::function<void()>& f, int iterations) {
  constexpr int kBatches = 21;
  std::vector<double> t(kBatches);
  for (int b = 0; b < kBatches; ++b) {
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < iterations; ++k) f();
    t[b] = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
               .count() /
           iterations;
  }
  std::nth_element(t.begin(), t.begin() + kBatches / 2, t.end());
  return t[kBatches / 2];
}

void describe(const Robot& robot, int iterations) {
  const Model& model = robot.model;
  Data data(model);
  int revolute = 0;
  for (const Joint& j : model.joints) revolute += j.type == JointType::Revolute;
  std::printf("\n%s  (%s)\n", robot.name.c_str(), robot.urdf_path.c_str());
  std::printf("  %d actuated joints, nq = %d, nv = %d, %d frames, mass %.2f kg\n", revolute,
              model.nq, model.nv, model.nframes(), model.totalMass());

  // Default posture: where the contacts and the centre of mass are.
  const Eigen::VectorXd& q0 = robot.default_q;
  framesForwardKinematics(model, data, q0);
  const Eigen::Vector3d com = centerOfMass(model, data, q0);
  std::printf("  default posture: base at z = %.3f m, centre of mass at (%.3f, %.3f, %.3f) m\n",
              q0[2], com.x(), com.y(), com.z());
  for (const ContactSpec& c : robot.contacts) {
    const SE3& oMf = data.oMf[model.getFrameId(c.frame)];
    std::printf("    %-8s %s contact at (%6.3f, %6.3f, %6.3f) m\n", c.frame.c_str(),
                c.dim == 3 ? "point  " : "surface", oMf.p.x(), oMf.p.y(), oMf.p.z());
  }
  // The mass matrix: how heavy the robot feels along its base motion and its joints.
  crba(model, data, q0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(data.M);
  std::printf("  joint-space inertia M(q0): eigenvalues in [%.2e, %.2e], condition %.1e\n",
              eig.eigenvalues().minCoeff(), eig.eigenvalues().maxCoeff(),
              eig.eigenvalues().maxCoeff() / eig.eigenvalues().minCoeff());

  // Timings on random states within the joint limits.
  std::mt19937 rng(1);
  const Eigen::VectorXd q = randomConfiguration(model, rng);
  const Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv),
                        a = Eigen::VectorXd::Random(model.nv);
  const struct {
    const char* name;
    std::function<void()> run;
  } algorithms[] = {
      {"forward kinematics", [&] { forwardKinematics(model, data, q); }},
      {"RNEA (inverse dynamics)", [&] { rnea(model, data, q, v, a); }},
      {"CRBA (mass matrix)", [&] { crba(model, data, q); }},
      {"ABA (forward dynamics)", [&] { aba(model, data, q, v, a); }},
      {"all joint Jacobians", [&] { computeJointJacobians(model, data, q); }},
      {"centre of mass", [&] { centerOfMass(model, data, q); }},
      {"centroidal momentum matrix", [&] { computeCentroidalMap(model, data, q); }},
  };
  std::printf("  %-28s %10s\n", "algorithm", "median");
  for (const auto& alg : algorithms)
    std::printf("  %-28s %7.2f us\n", alg.name, medianMicroseconds(alg.run, iterations));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Stride dynamics demo: the in-house robots and the cost of each algorithm"};
  stride::commandLineConventions(app, "stride-dynamics-demo");
  std::string config_dir = STRIDE_CONFIG_DIR;
  int iterations = 2000;
  app.add_option("--config-dir", config_dir, "folder holding robots/<name>/<name>.yaml");
  app.add_option("--iterations", iterations, "calls per timing batch")->check(CLI::PositiveNumber);
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;
  std::printf("Stride dynamics core: rigid-body algorithms on the in-house robots\n");
  try {
    for (const char* name : {"stride_quad", "stride_humanoid"})
      describe(loadRobot(config_dir + "/robots/" + name + "/" + name + ".yaml"), iterations);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  std::printf("\nBenchmarks with repetitions and JSON: tools/bench/run.sh\n");
  return 0;
}
