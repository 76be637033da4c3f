// stride-check-dynamics REF.json [--robots-dir DIR]
//
// Recomputes, for every sample of a reference file (format: ../shared/reference/README.md), every
// quantity Stride provides, and prints one line per quantity with the largest error over the
// samples, max|x - ref| / max(1, max|ref|). Exits 1 when any computed quantity is above its
// tolerance, 2 when the file or the robot cannot be loaded. Quantities the file holds that Stride
// does not compute yet are listed as "not yet computed"; keys it does not know are listed too.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/command_line.hpp"
#include "solver/contact/contact_dynamics.hpp"
#include "solver/multibody/aba.hpp"
#include "solver/multibody/aba_derivatives.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/rnea.hpp"
#include "solver/multibody/rnea_derivatives.hpp"
#include "solver/multibody/urdf.hpp"

namespace fs = std::filesystem;
using namespace stride;

namespace {

constexpr double kTolerance = 1e-8;
constexpr double kDerivativeTolerance = 1e-7;

using json = nlohmann::json;

// A JSON array of numbers; throws on anything else (the caller reports the quantity as failed).
Eigen::VectorXd toVector(const json& node) {
  if (!node.is_array()) throw std::runtime_error("expected an array of numbers");
  Eigen::VectorXd v(static_cast<Eigen::Index>(node.size()));
  for (std::size_t k = 0; k < node.size(); ++k)
    v[static_cast<Eigen::Index>(k)] = node[k].get<double>();
  return v;
}

// max|x - ref| / max(1, max|ref|); +inf when the sizes differ or x is not finite.
double relativeError(const Eigen::VectorXd& x, const Eigen::VectorXd& ref) {
  if (x.size() != ref.size() || !x.allFinite()) return std::numeric_limits<double>::infinity();
  if (ref.size() == 0) return 0.0;
  return (x - ref).cwiseAbs().maxCoeff() / std::max(1.0, ref.cwiseAbs().maxCoeff());
}

Eigen::VectorXd rowMajor(const Eigen::MatrixXd& m) {
  Eigen::VectorXd out(m.size());
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out[r * m.cols() + c] = m(r, c);
  return out;
}

struct Sample {
  Eigen::VectorXd q, v, a, tau;
};

// A quantity Stride computes: the error of one sample, or nullopt when the sample lacks it.
using Check = std::function<std::optional<double>(const json& sample, const Sample& s)>;

struct Quantity {
  std::string name;
  double tolerance;
  Check check;  // empty: not yet computed
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Check Stride's dynamics against reference values from an independent library"};
  stride::commandLineConventions(app, "stride-check-dynamics");
  std::string ref_path, robots_dir = "../shared/robots";
  app.add_option("reference", ref_path, "reference JSON file")->required();
  app.add_option("--robots-dir", robots_dir,
                 "folder the reference's `urdf` path is relative to (default ../shared/robots, "
                 "else the robots/ folder beside the reference's folder)");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;

  json parsed;
  try {
    std::ifstream file(ref_path);
    if (!file) throw std::runtime_error("cannot open it");
    parsed = json::parse(file);
    if (!parsed.is_object()) throw std::runtime_error("not a JSON object");
  } catch (const std::exception& e) {
    std::cerr << "error: cannot read reference '" << ref_path << "': " << e.what() << "\n";
    return 2;
  }
  for (const char* key : {"robot", "urdf", "root_joint", "nq", "nv", "samples"})
    if (!parsed.contains(key)) {
      std::cerr << "error: reference '" << ref_path << "' has no '" << key << "' entry\n";
      return 2;
    }
  // Read-only from here: at() throws on a missing key where operator[] would add it.
  const json& ref = parsed;

  fs::path dir = robots_dir;
  if (!app.count("--robots-dir") && !fs::exists(dir / ref.at("urdf").get<std::string>()))
    dir = fs::path(ref_path).parent_path() / ".." / "robots";
  const fs::path urdf = dir / ref.at("urdf").get<std::string>();
  const std::string root = ref.at("root_joint").get<std::string>();
  if (root != "free-flyer" && root != "fixed") {
    std::cerr << "error: unknown root_joint '" << root << "' (free-flyer or fixed)\n";
    return 2;
  }

  Model model;
  std::vector<MimicJoint> mimics;
  try {
    // Mimic joints as independent joints, as the reference libraries' URDF parsers load them.
    model = buildModelFromUrdf(urdf.string(),
                               root == "fixed" ? RootJoint::Fixed : RootJoint::FreeFlyer);
    mimics = urdfMimicJoints(urdf.string());
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  if (!mimics.empty())
    std::printf(
        "note: %zu <mimic> joints (%s, ...) loaded as independent joints, their coupling "
        "not modelled\n",
        mimics.size(), mimics.front().name.c_str());
  if (ref.contains("gravity")) model.gravity = toVector(ref.at("gravity"));
  Data data(model);
  // The reference closes all listed contacts at once, forces in each contact frame (LOCAL).
  ContactSet contacts;
  try {
    if (ref.contains("contacts"))
      for (const auto& c : ref.at("contacts"))
        contacts.add(model, c.at("frame").get<std::string>(), c.at("dim").get<int>());
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  ContactData cdata(model, contacts);

  std::printf("robot %s (%s): nq %d, nv %d, %d joints, %d frames, %zu samples\n",
              ref.at("robot").get<std::string>().c_str(), urdf.string().c_str(), model.nq, model.nv,
              model.njoints() - 1, model.nframes(), ref.at("samples").size());

  // Structure first: a different joint order would make every comparison meaningless.
  bool structure_ok = model.nq == ref.at("nq").get<int>() && model.nv == ref.at("nv").get<int>();
  if (ref.contains("joint_names")) {
    std::vector<std::string> ours;
    for (int i = 1; i < model.njoints(); ++i)
      if (model.joints[i].type != JointType::FreeFlyer) ours.push_back(model.joints[i].name);
    const auto theirs = ref.at("joint_names").get<std::vector<std::string>>();
    if (ours != theirs) {
      std::printf("%-22s FAIL (joint order differs from the reference)\n", "joint_names");
      structure_ok = false;
    } else {
      std::printf("%-22s ok (%zu joints, same order)\n", "joint_names", ours.size());
    }
  }
  if (!structure_ok) {
    std::printf("FAIL: model dimensions or joint order differ from the reference\n");
    return 1;
  }
  bool all_ok = true;
  if (ref.contains("total_mass")) {
    // The reference sums every body, including those fixed to the world (a fixed base).
    const double m = model.totalMass() + model.fixedMass();
    const double err = std::abs(m - ref.at("total_mass").get<double>()) / std::max(1.0, m);
    const bool ok = err <= kTolerance;
    all_ok &= ok;
    std::printf("%-22s %.3e  %s\n", "total_mass", err, ok ? "ok" : "FAIL");
  }

  auto vec = [](const json& s, const char* key) { return toVector(s.at(key)); };
  std::vector<Quantity> quantities = {
      {"rnea", kTolerance,
       [&](const json& n, const Sample& s) {
         return relativeError(rnea(model, data, s.q, s.v, s.a), vec(n, "rnea"));
       }},
      {"mass_matrix", kTolerance,
       [&](const json& n, const Sample& s) {
         return relativeError(rowMajor(crba(model, data, s.q)), vec(n, "mass_matrix"));
       }},
      {"nonlinear_effects", kTolerance,
       [&](const json& n, const Sample& s) {
         return relativeError(nonLinearEffects(model, data, s.q, s.v), vec(n, "nonlinear_effects"));
       }},
      {"gravity_torque", kTolerance,
       [&](const json& n, const Sample& s) {
         return relativeError(computeGeneralizedGravity(model, data, s.q),
                              vec(n, "gravity_torque"));
       }},
      {"aba", kTolerance,
       [&](const json& n, const Sample& s) {
         return relativeError(aba(model, data, s.q, s.v, s.tau), vec(n, "aba"));
       }},
      {"com", kTolerance,
       [&](const json& n, const Sample& s) {
         return relativeError(centerOfMass(model, data, s.q), vec(n, "com"));
       }},
      {"centroidal_momentum", kTolerance,
       [&](const json& n, const Sample& s) {
         return relativeError(computeCentroidalMomentum(model, data, s.q, s.v),
                              vec(n, "centroidal_momentum"));
       }},
      {"frames", kTolerance,
       [&](const json& n, const Sample& s) -> std::optional<double> {
         computeJointJacobians(model, data, s.q);
         updateFramePlacements(model, data);
         Matrix6Xd J(6, model.nv);
         double worst = 0;
         for (const auto& entry : n.at("frames").items()) {
           const std::string& name = entry.key();
           if (!model.existFrame(name)) {
             std::printf("  frame '%s' does not exist in the model\n", name.c_str());
             return std::numeric_limits<double>::infinity();
           }
           const int id = model.getFrameId(name);
           const json& f = entry.value();
           worst = std::max(worst, relativeError(data.oMf[id].p, toVector(f.at("translation"))));
           worst =
               std::max(worst, relativeError(rowMajor(data.oMf[id].R), toVector(f.at("rotation"))));
           getFrameJacobian(model, data, id, ReferenceFrame::LocalWorldAligned, J);
           worst = std::max(
               worst, relativeError(rowMajor(J), toVector(f.at("jacobian_local_world_aligned"))));
         }
         return worst;
       }},
      // Provided by the derivatives and contact dynamics issue.
      {"drnea_dq", kDerivativeTolerance,
       [&](const json& n, const Sample& s) {
         computeRNEADerivatives(model, data, s.q, s.v, s.a);
         return relativeError(rowMajor(data.dtau_dq), vec(n, "drnea_dq"));
       }},
      {"drnea_dv", kDerivativeTolerance,
       [&](const json& n, const Sample& s) {
         computeRNEADerivatives(model, data, s.q, s.v, s.a);
         return relativeError(rowMajor(data.dtau_dv), vec(n, "drnea_dv"));
       }},
      {"daba_dq", kDerivativeTolerance,
       [&](const json& n, const Sample& s) {
         computeABADerivatives(model, data, s.q, s.v, s.tau);
         return relativeError(rowMajor(data.ddq_dq), vec(n, "daba_dq"));
       }},
      {"daba_dv", kDerivativeTolerance,
       [&](const json& n, const Sample& s) {
         computeABADerivatives(model, data, s.q, s.v, s.tau);
         return relativeError(rowMajor(data.ddq_dv), vec(n, "daba_dv"));
       }},
      {"contact_dynamics", kTolerance,
       [&](const json& n, const Sample& s) -> std::optional<double> {
         const json& cd = n.at("contact_dynamics");
         const Eigen::VectorXd tau = toVector(cd.at("tau"));
         if (contactDynamics(model, data, contacts, cdata, s.q, s.v, tau) != ContactStatus::Ok)
           return std::numeric_limits<double>::infinity();
         return std::max(
             {relativeError(cdata.gamma.head(cdata.nc), toVector(cd.at("constraint_drift"))),
              relativeError(cdata.ddq, toVector(cd.at("ddq"))),
              relativeError(cdata.lambda.head(cdata.nc), toVector(cd.at("forces")))});
       }},
      {"impulse_dynamics", kTolerance,
       [&](const json& n, const Sample& s) -> std::optional<double> {
         const json& id = n.at("impulse_dynamics");
         const double r = id.contains("restitution") ? id.at("restitution").get<double>() : 0.0;
         if (impulseDynamics(model, data, contacts, cdata, s.q, toVector(id.at("v_before")), r) !=
             ContactStatus::Ok)
           return std::numeric_limits<double>::infinity();
         return std::max(relativeError(cdata.v_after, toVector(id.at("v_after"))),
                         relativeError(cdata.impulses.head(cdata.nc), toVector(id.at("impulses"))));
       }},
  };

  const std::set<std::string> inputs = {"q", "v", "a", "tau"};
  std::set<std::string> known(inputs);
  for (const auto& qd : quantities) known.insert(qd.name);
  std::set<std::string> unknown;

  std::map<std::string, double> worst;
  std::map<std::string, int> seen;
  for (const auto& sample : ref.at("samples")) {
    for (const auto& entry : sample.items())
      if (!known.count(entry.key())) unknown.insert(entry.key());
    Sample s{vec(sample, "q"), vec(sample, "v"), vec(sample, "a"), vec(sample, "tau")};
    for (const auto& qd : quantities) {
      if (!sample.contains(qd.name)) continue;
      ++seen[qd.name];
      if (!qd.check) continue;
      double err;
      try {
        err = qd.check(sample, s).value_or(0.0);
      } catch (const std::exception& e) {
        std::printf("  %s: %s\n", qd.name.c_str(), e.what());
        err = std::numeric_limits<double>::infinity();
      }
      worst[qd.name] = std::max(worst[qd.name], err);
    }
  }

  for (const auto& qd : quantities) {
    if (!seen.count(qd.name)) {
      std::printf("%-22s -          not in this reference file\n", qd.name.c_str());
    } else if (!qd.check) {
      std::printf("%-22s -          not yet computed (%d samples)\n", qd.name.c_str(),
                  seen[qd.name]);
    } else {
      const bool ok = worst[qd.name] <= qd.tolerance;
      all_ok &= ok;
      std::printf("%-22s %.3e  %s (tolerance %.0e, %d samples)\n", qd.name.c_str(), worst[qd.name],
                  ok ? "ok" : "FAIL", qd.tolerance, seen[qd.name]);
    }
  }
  for (const auto& k : unknown)
    std::printf("%-22s -          unknown key, not checked\n", k.c_str());
  std::printf("%s\n", all_ok ? "PASS" : "FAIL");
  return all_ok ? 0 : 1;
}
