#pragma once
// LCM messages -> the JSON frames the page draws (viz/README.md, "Frames"), computed with
// Stride's own libraries: forward kinematics of the contact frames along a predicted trajectory,
// and the contact forces at a measured state estimated with the KKT contact dynamics (paper eq. 10,
// solver/contact) under the torque the robot applies there (messages/policy_interpolation.hpp).
// Every input is a message that already passed its checks (messages/validate.hpp,
// viz/server/wire.hpp) for the robot given here.

#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "config/robot_config.hpp"
#include "messages/policy_interpolation.hpp"
#include "solver/contact/contact_dynamics.hpp"
#include "stride/command_t.hpp"
#include "stride/horizon_t.hpp"
#include "stride/mpc_status_t.hpp"
#include "stride/policy_t.hpp"
#include "stride/robot_model_t.hpp"
#include "stride/robot_state_t.hpp"
#include "stride/terrain_t.hpp"

namespace stride::viz {

using Json = nlohmann::json;

// A model hash as the programs print it (16 hex digits: msg::formatHash).
std::string hashText(std::int64_t hash);

// How the state frames' forces went: "forces" is [] unless estimated.
struct ForceCounts {
  long estimated = 0;
  long no_policy = 0;         // no policy yet: no torque to estimate with
  long no_contact_flags = 0;  // the state reports no contact flags: which contacts hold is unknown
  long failed = 0;            // the contact solve failed (singular, non-finite)
};

class FrameBuilder {
 public:
  // Keeps a reference to `robot`: it must outlive the builder.
  explicit FrameBuilder(const Robot& robot);
  ~FrameBuilder();

  // {"type":"model",...}: from the controller's robot_model_t when given, else from the robot.
  Json model(const robot_model_t* wire) const;

  // A policy the robot applies from now on; returns its serial (1, 2, ...). The builder holds the
  // newest kPolicies: a state can be estimated with the policy the robot held when it published
  // that state, even after newer ones came (viz/README.md, "How forces are estimated").
  static constexpr int kPolicies = 3;
  std::uint64_t setPolicy(const policy_t& policy);
  bool hasPolicy() const { return serial_ > 0; }
  std::uint64_t policySerial() const { return serial_; }  // the newest's; 0 before any

  // {"type":"state","t","q","contact","forces"}: forces per contact frame, world axes [N], zero
  // for open contacts, estimated at the state with the torque the robot applies there: the policy
  // of that serial (the newest one when 0, or when it is no longer held) at the state's time,
  // clamped to the model's effort limits.
  Json state(const robot_state_t& state, std::uint64_t policy_serial = 0);
  // The torque of the last estimate (size nu), after clamping.
  const Eigen::VectorXd& lastTorque() const { return u_; }
  // {"type":"plan","t","base","feet","footholds","forces","chosen_footholds"} from the
  // controller's horizon; chosen_footholds: the gait generator's, [x, y, z, contact, time after t,
  // source] each.
  Json plan(const horizon_t& horizon);
  // The same from a policy's x_ref knots: no contact mask per knot (only at knot 0: footholds of
  // the stances under way), no planned forces ([]) and no chosen footholds ([]).
  Json plan(const policy_t& policy);
  // {"type":"status",...}; `requested`: the newest command_t seen, if any.
  static Json status(const mpc_status_t& status, const command_t* requested);
  // {"type":"terrain","t","origin_x","origin_y","resolution","rows","cols","heights"}: heights
  // row-major (rows along world y), rounded to kTerrainHeightStep, null where unknown (NaN).
  static constexpr double kTerrainHeightStep = 1e-3;
  static Json terrain(const terrain_t& map);

  const ForceCounts& forceCounts() const { return force_counts_; }

 private:
  // Contact frame positions (world) at configuration q: FK into data_, feet_ filled.
  void feetAt(const Eigen::VectorXd& q);
  Json planFrom(double t, const std::vector<const std::vector<double>*>& qs,
                const std::vector<std::int32_t>& masks, Json forces);
  bool estimateForces(const robot_state_t& state, std::uint64_t policy_serial, Json& forces);

  // A received policy in the evaluator's form, its times relative to knot 0.
  struct HeldPolicy {
    msg::Policy policy;
    std::int64_t knot0_utime = 0;
    std::uint64_t serial = 0;  // 0: empty
  };

  const Robot& robot_;
  int nu_;
  Data data_;
  ContactSet contacts_;
  ContactData contact_data_;
  msg::PolicyEvaluator evaluator_;
  std::array<HeldPolicy, kPolicies> policies_;
  std::uint64_t serial_ = 0;
  Eigen::VectorXd q_, v_, u_, tau_, effort_;
  std::vector<Eigen::Vector3d> feet_;
  ForceCounts force_counts_;
};

}  // namespace stride::viz
