#include "locomotion/gait.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

namespace stride {

std::vector<std::string> gaitNames(int contacts) {
  if (contacts == 4) return {"stand", "trot", "walk", "pace", "pronk", "bound", "flying_trot"};
  if (contacts == 2) return {"stand", "walk", "hop"};
  return {"stand"};
}

bool hasFlight(const std::string& gait) {
  return gait == "pronk" || gait == "bound" || gait == "flying_trot" || gait == "hop";
}

ContactPlan makeGaitPattern(const std::string& gait, const GaitTiming& timing,
                            const std::vector<ContactSpec>& contacts) {
  const int nc = static_cast<int>(contacts.size());
  const std::vector<std::string> known = gaitNames(nc);
  if (std::find(known.begin(), known.end(), gait) == known.end())
    throw ConfigError("gait '" + gait + "' is not one a robot with " + std::to_string(nc) +
                      " contacts walks with");
  const double second = hasFlight(gait) ? timing.flight : timing.swing;
  if (!(timing.support > 0.0) || !(second > 0.0) || !std::isfinite(timing.support) ||
      !std::isfinite(second))
    throw ConfigError("gait '" + gait + "': support and " + (hasFlight(gait) ? "flight" : "swing") +
                      " must be positive");
  std::vector<std::string> all;
  for (const ContactSpec& c : contacts) all.push_back(c.frame);
  auto without = [&](std::initializer_list<int> lifted) {
    std::vector<std::string> closed;
    for (int c = 0; c < nc; ++c)
      if (std::find(lifted.begin(), lifted.end(), c) == lifted.end()) closed.push_back(all[c]);
    return closed;
  };
  ContactPlan plan;
  plan.cyclic = true;
  const double s = timing.support, w = timing.swing, f = timing.flight;
  if (gait == "stand") {
    plan.phases = {{s, all}};
  } else if (gait == "pronk" || gait == "hop") {
    plan.phases = {{s, all}, {f, {}}};
  } else if (gait == "bound") {
    plan.phases = {{s, without({2, 3})}, {f, {}}, {s, without({0, 1})}, {f, {}}};
  } else if (gait == "flying_trot") {
    plan.phases = {{s, without({1, 2})}, {f, {}}, {s, without({0, 3})}, {f, {}}};
  } else if (gait == "trot") {
    plan.phases = {{s, all}, {w, without({0, 3})}, {s, all}, {w, without({1, 2})}};
  } else if (gait == "pace") {
    plan.phases = {{s, all}, {w, without({0, 2})}, {s, all}, {w, without({1, 3})}};
  } else if (nc == 4) {  // walk
    for (int foot : {2, 0, 3, 1}) {
      plan.phases.push_back({s, all});
      plan.phases.push_back({w, without({foot})});
    }
  } else {  // biped walk
    plan.phases = {{s, all}, {w, without({0})}, {s, all}, {w, without({1})}};
  }
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

}  // namespace stride
