#include "sim/plant.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace stride::sim {

bool PlantOptions::enabled() const {
  return !mass_scale.empty() || payload != 0.0 || !com_offset.isZero() || torque_limit_scale != 1.0;
}

bool parseMassScale(const std::string& text, std::pair<std::string, double>& scale) {
  const std::size_t colon = text.rfind(':');
  const std::string body = colon == std::string::npos ? "" : text.substr(0, colon);
  const std::string number = colon == std::string::npos ? text : text.substr(colon + 1);
  if (number.empty() || (colon != std::string::npos && body.empty())) return false;
  char* end = nullptr;
  const double factor = std::strtod(number.c_str(), &end);
  if (end == number.c_str() || *end != '\0' || !std::isfinite(factor) || !(factor > 0.0))
    return false;
  scale = {body, factor};
  return true;
}

namespace {
Inertia scaled(const Inertia& Y, double factor) {
  Inertia out = Y;
  out.m *= factor;
  out.h *= factor;
  out.I *= factor;
  return out;
}
}  // namespace

Robot plantOf(const Robot& robot, const PlantOptions& options) {
  Robot plant = robot;
  Model& model = plant.model;
  for (const auto& [body, factor] : options.mass_scale) {
    if (body.empty()) {
      for (int j = 1; j < model.njoints(); ++j)
        model.inertias[j] = scaled(model.inertias[j], factor);
      continue;
    }
    // "base": the free-flyer's body, whatever its link is called.
    if (body == "base" && !model.existFrame(body) && model.hasFreeFlyer()) {
      model.inertias[1] = scaled(model.inertias[1], factor);
      continue;
    }
    if (!model.existFrame(body))
      throw std::invalid_argument("--mass-scale: the robot '" + robot.name + "' has no body '" +
                                  body + "'");
    const int joint = model.frames[model.getFrameId(body)].parentJoint;
    if (joint == 0)
      throw std::invalid_argument("--mass-scale: '" + body + "' is fixed to the world");
    model.inertias[joint] = scaled(model.inertias[joint], factor);
  }
  const int carrier = model.hasFreeFlyer() ? 1 : model.njoints() - 1;
  if (!(options.com_offset.isZero())) {
    const Inertia& Y = model.inertias[carrier];
    if (!(Y.m > 0.0)) throw std::invalid_argument("--com-offset: the base has no mass");
    model.inertias[carrier] =
        Inertia::FromMassComInertia(Y.m, Y.com() + options.com_offset, Y.inertiaAboutCom());
  }
  if (!(options.payload >= 0.0) || !std::isfinite(options.payload) ||
      !options.payload_at.allFinite())
    throw std::invalid_argument("--payload: the mass must be >= 0 and the offset finite");
  if (options.payload > 0.0)
    model.appendBodyToJoint(
        carrier,
        Inertia::FromMassComInertia(options.payload, options.payload_at, Eigen::Matrix3d::Zero()));
  if (!(options.torque_limit_scale > 0.0) || !std::isfinite(options.torque_limit_scale))
    throw std::invalid_argument("--torque-limit-scale: must be > 0");
  const int first = model.hasFreeFlyer() ? 6 : 0;
  model.effortLimit.tail(model.nv - first) *= options.torque_limit_scale;
  return plant;
}

}  // namespace stride::sim
