#include "sim/command_line.hpp"

#include <cstdio>

namespace stride::sim {

void addMockRobotOptions(CLI::App& app, SimNodeOptions& node, SimOptions& physics,
                         MockRobotArgs& args) {
  SensingOptions& s = node.sensing;
  const char* sensing = "Sensing (what the robot's low-level loop and the controller see)";
  app.add_option("--noise-q", s.encoder_noise,
                 "joint encoders' noise, std [rad] (the base's pose: --orientation-noise, "
                 "--base-position-noise)")
      ->group(sensing);
  app.add_option("--encoder-resolution", s.encoder_resolution,
                 "joint encoders' count [rad]: readings are multiples of it")
      ->group(sensing);
  app.add_option("--noise-v", args.noise_v,
                 "shorthand: the same std on every velocity component (joints [rad/s], base "
                 "linear [m/s], gyro [rad/s])")
      ->group(sensing);
  app.add_option("--joint-velocity-noise", s.joint_velocity_noise, "joint velocities' noise, std")
      ->group(sensing);
  app.add_option("--joint-velocity-filter", s.joint_velocity_filter,
                 "joint velocities from the encoders' finite difference low-passed at this "
                 "cutoff [Hz] (0: measured)")
      ->group(sensing);
  app.add_option("--orientation-noise", s.orientation_noise,
                 "base orientation estimate's noise, std per axis [rad]")
      ->group(sensing);
  app.add_option("--gyro-noise", s.gyro_noise, "gyro (base angular velocity) noise, std [rad/s]")
      ->group(sensing);
  app.add_option("--gyro-bias-walk", s.gyro_bias_walk,
                 "gyro bias random walk [rad/s/sqrt(s)]; its z drifts the yaw estimate")
      ->group(sensing);
  app.add_option("--base-position-noise", s.base_position_noise,
                 "base position estimate's noise, std [m]")
      ->group(sensing);
  app.add_option("--base-velocity-noise", s.base_velocity_noise,
                 "base linear velocity estimate's noise, std [m/s]")
      ->group(sensing);
  app.add_option("--velocity-estimator", s.velocity_estimator,
                 "base linear velocity from a complementary filter of the legs' odometry (its "
                 "noise: --base-velocity-noise) and the accelerometer, crossover [Hz] (0: the "
                 "legs' velocity as is)")
      ->group(sensing);
  app.add_option("--accel-noise", s.accel_noise,
                 "the velocity estimator's accelerometer noise, std [m/s^2]")
      ->group(sensing);
  app.add_option("--base-drift", s.base_drift,
                 "base position estimate's drift on x and y, random walk [m/sqrt(s)]")
      ->group(sensing);
  app.add_option("--sensor-latency", s.latency,
                 "every estimate measures the state this many physics steps (1 ms) earlier")
      ->group(sensing);
  app.add_option("--sensor-drop", s.sample_drop,
                 "probability that a sensor sample is lost (the previous estimate is kept)")
      ->group(sensing);
  app.add_option("--delay", node.delay,
                 "estimates reach the controller this many publications late (whole periods)")
      ->group(sensing);
  app.add_option("--drop", node.drop,
                 "probability that an estimate is dropped on its way to the controller")
      ->group(sensing);
  app.add_option("--seed", node.seed, "the random seed of every noise, drift and drop (1)")
      ->group(sensing);

  ActuatorOptions& a = node.actuators;
  const char* actuators = "Actuators (between the commanded and the applied torque)";
  app.add_option("--torque-latency", a.latency, "torques act this many physics steps late")
      ->group(actuators);
  app.add_option("--torque-bandwidth", a.bandwidth, "first-order torque lag's cutoff [Hz]")
      ->group(actuators);
  app.add_option("--torque-scale", a.torque_scale,
                 "motors give this times the commanded torque (a torque constant off)")
      ->group(actuators);
  app.add_flag("--velocity-limits", a.velocity_limits,
               "torque-speed envelope: tau_max (1 - |w| / w_max) left in the direction of motion, "
               "from the URDF's effort and velocity limits")
      ->group(actuators);
  app.add_option("--joint-friction", a.friction, "Coulomb friction in every joint [Nm]")
      ->group(actuators);
  app.add_option("--joint-damping", a.damping, "viscous damping in every joint [Nm s/rad]")
      ->group(actuators);

  const char* plant = "Model mismatch (the robot differs; the controller's model does not)";
  app.add_option("--mass-scale", args.mass_scales,
                 "BODY:F, or F for every body: that body's mass and inertia times F (repeatable)")
      ->group(plant);
  app.add_option("--payload", args.payload,
                 "KG DX DY DZ: a point mass on the base at that offset in its axes [kg, m]")
      ->expected(4)
      ->group(plant);
  app.add_option("--com-offset", args.com_offset,
                 "DX DY DZ: the base's centre of mass moved by this much in its axes [m]")
      ->expected(3)
      ->group(plant);
  app.add_option("--torque-limit-scale", node.plant.torque_limit_scale,
                 "every joint's effort limit times this")
      ->group(plant);
  app.add_option("--mu", physics.friction, "ground friction coefficient (0.8)")->group(plant);
}

bool finishMockRobotOptions(const MockRobotArgs& args, SimNodeOptions& node, const char* program) {
  if (args.noise_v > 0.0) {
    node.sensing.joint_velocity_noise = args.noise_v;
    node.sensing.base_velocity_noise = args.noise_v;
    node.sensing.gyro_noise = args.noise_v;
  }
  for (const std::string& text : args.mass_scales) {
    std::pair<std::string, double> scale;
    if (!parseMassScale(text, scale)) {
      std::fprintf(stderr, "%s: --mass-scale '%s': expected BODY:F or F, F > 0\n", program,
                   text.c_str());
      return false;
    }
    node.plant.mass_scale.push_back(scale);
  }
  if (args.payload.size() == 4) {
    node.plant.payload = args.payload[0];
    node.plant.payload_at = Eigen::Vector3d(args.payload[1], args.payload[2], args.payload[3]);
  }
  if (args.com_offset.size() == 3)
    node.plant.com_offset =
        Eigen::Vector3d(args.com_offset[0], args.com_offset[1], args.com_offset[2]);
  try {
    node.sensing.check();
    node.actuators.check();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return false;
  }
  return true;
}

std::string describeMockRobot(const SimNodeOptions& node, const SimOptions& physics) {
  std::string out;
  char text[200];
  auto add = [&](const char* what) {
    if (!out.empty()) out += ", ";
    out += what;
  };
  const SensingOptions& s = node.sensing;
  if (s.enabled()) {
    std::snprintf(text, sizeof text,
                  "sensing (latency %d steps, encoders %g rad / %g rad count, joint velocity %g, "
                  "orientation %g rad, gyro %g, base %g m / %g m/s)",
                  s.latency, s.encoder_noise, s.encoder_resolution, s.joint_velocity_noise,
                  s.orientation_noise, s.gyro_noise, s.base_position_noise, s.base_velocity_noise);
    add(text);
  }
  const ActuatorOptions& a = node.actuators;
  if (a.enabled()) {
    std::snprintf(text, sizeof text,
                  "actuators (latency %d steps, %g Hz, scale %g, %s, friction %g, damping %g)",
                  a.latency, a.bandwidth, a.torque_scale,
                  a.velocity_limits ? "torque-speed envelope" : "no envelope", a.friction,
                  a.damping);
    add(text);
  }
  const PlantOptions& p = node.plant;
  if (p.enabled()) {
    std::snprintf(text, sizeof text,
                  "plant (%zu mass scales, payload %g kg, com offset %.3f %.3f %.3f m, torque "
                  "limits x %g)",
                  p.mass_scale.size(), p.payload, p.com_offset.x(), p.com_offset.y(),
                  p.com_offset.z(), p.torque_limit_scale);
    add(text);
  }
  if (physics.friction != SimOptions{}.friction) {
    std::snprintf(text, sizeof text, "ground mu %g", physics.friction);
    add(text);
  }
  if (node.delay > 0 || node.drop > 0.0) {
    std::snprintf(text, sizeof text, "estimates to the controller %d periods late, %g dropped",
                  node.delay, node.drop);
    add(text);
  }
  return out;
}

}  // namespace stride::sim
