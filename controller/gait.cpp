#include "controller/gait.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>

namespace stride {

ContactPlan makeGaitPlan(const GaitConfig& gait, const std::vector<ContactSpec>& contacts) {
  const int nc = static_cast<int>(contacts.size());
  std::vector<std::string> all;
  for (const ContactSpec& c : contacts) all.push_back(c.frame);
  auto without = [&](std::initializer_list<int> lifted) {
    std::vector<std::string> closed;
    for (int c = 0; c < nc; ++c) {
      bool up = false;
      for (int l : lifted) up = up || l == c;
      if (!up) closed.push_back(all[c]);
    }
    return closed;
  };

  std::vector<ContactPhase> cycle;
  if (gait.type == "trot") {
    if (nc != 4) throw ConfigError("gait 'trot' needs 4 contacts (FL, FR, HL, HR)");
    cycle = {{gait.support, all},
             {gait.swing, without({0, 3})},
             {gait.support, all},
             {gait.swing, without({1, 2})}};
  } else if (gait.type == "walk" && nc == 4) {
    for (int foot : {2, 0, 3, 1}) {
      cycle.push_back({gait.support, all});
      cycle.push_back({gait.swing, without({foot})});
    }
  } else if (gait.type == "walk" && nc == 2) {
    cycle = {{gait.support, all},
             {gait.swing, without({0})},
             {gait.support, all},
             {gait.swing, without({1})}};
  } else if (gait.type == "walk") {
    throw ConfigError("gait 'walk' needs 2 (biped) or 4 (quadruped) contacts");
  }

  ContactPlan plan;
  plan.cyclic = false;
  // Never a zero-length phase: a plan of only standing still has one phase.
  plan.phases.push_back({std::max(gait.stand, 1e-3), all});
  if (!cycle.empty()) {
    double cycle_time = 0.0;
    for (const ContactPhase& p : cycle) cycle_time += p.duration;
    const long cycles =
        std::max(0L, static_cast<long>(std::floor((gait.duration - gait.stand) / cycle_time)));
    for (long i = 0; i < cycles; ++i)
      for (const ContactPhase& p : cycle) plan.phases.push_back(p);
  }
  plan.phases.push_back({1.0, all});  // stand at the end (held past it)
  return plan;
}

ContactPlan loadContactPlan(const std::string& path) {
  auto fail = [&](const std::string& what) -> ContactPlan {
    throw ConfigError("contact plan '" + path + "': " + what);
  };
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return fail("file does not exist or cannot be read");
  } catch (const YAML::Exception& e) {
    return fail(std::string("malformed YAML: ") + e.what());
  }
  ContactPlan plan;
  try {
    if (!root.IsMap() || !root["phases"] || !root["phases"].IsSequence())
      return fail("needs a 'phases' list");
    plan.cyclic = root["cyclic"] ? root["cyclic"].as<bool>() : false;
    int i = 0;
    for (const auto& p : root["phases"]) {
      if (!p["duration"] || !p["contacts"])
        return fail("phase " + std::to_string(i) + " needs 'duration' and 'contacts'");
      plan.phases.push_back(
          {p["duration"].as<double>(), p["contacts"].as<std::vector<std::string>>()});
      ++i;
    }
    plan.validateTiming();
  } catch (const YAML::Exception& e) {
    return fail(std::string("wrong type: ") + e.what());
  } catch (const std::invalid_argument& e) {
    return fail(e.what());
  }
  return plan;
}

ContactPlan makePlan(const GaitConfig& gait, const std::vector<ContactSpec>& contacts) {
  return gait.plan_file.empty() ? makeGaitPlan(gait, contacts) : loadContactPlan(gait.plan_file);
}

}  // namespace stride
