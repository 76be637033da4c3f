#include "tools/paper/centroidal_planner.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/data.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;

double smoothstep(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * (3.0 - 2.0 * s);
}

// One walking phase: double support (swing = -1) or the single support of a step.
struct Phase {
  double t0, t1;
  int swing;                   // foot in the air, -1 in double support
  Eigen::Vector2d zmp0, zmp1;  // ZMP reference at the start and the end (ramped smoothly)
  Eigen::Vector3d from, to;    // the swing foot's footholds
};

// The cart-table CoM along one axis: least squares on the ZMP error, the jerk and the rest
// conditions at both ends (see the header).
Eigen::VectorXd cartTable(const Eigen::VectorXd& p_ref, double z_over_g, double dt, double w_jerk) {
  const int n = static_cast<int>(p_ref.size());  // N + 1 samples
  const double w_bc = 1e3;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  auto addRow = [&](const std::vector<std::pair<int, double>>& row, double target, double w) {
    for (const auto& [i, a] : row) {
      g[i] += w * a * target;
      for (const auto& [j, b] : row) H(i, j) += w * a * b;
    }
  };
  const double k2 = z_over_g / (dt * dt);
  for (int k = 1; k + 1 < n; ++k)
    addRow({{k - 1, -k2}, {k, 1.0 + 2.0 * k2}, {k + 1, -k2}}, p_ref[k], 1.0);
  const double k3 = 1.0 / (dt * dt * dt);
  for (int k = 1; k + 2 < n; ++k)
    addRow({{k - 1, -k3}, {k, 3.0 * k3}, {k + 1, -3.0 * k3}, {k + 2, k3}}, 0.0, w_jerk);
  addRow({{0, 1.0}}, p_ref[0], w_bc);
  addRow({{0, -1.0}, {1, 1.0}}, 0.0, w_bc);
  addRow({{n - 1, 1.0}}, p_ref[n - 1], w_bc);
  addRow({{n - 2, -1.0}, {n - 1, 1.0}}, 0.0, w_bc);
  return H.ldlt().solve(g);
}
}  // namespace

StridePlan planStrides(const Model& model, const Eigen::VectorXd& q_stand,
                       const std::array<std::string, 2>& feet, const StridePlanOptions& o) {
  if (!(o.stride > 0.0) || o.strides < 0 || !(o.dt > 0.0) || !(o.t_single > 0.0) ||
      !(o.t_double > 0.0) || !(o.t_rest > 0.0) || !(o.leg_reach > 0.0 && o.leg_reach < 1.0))
    throw std::invalid_argument("planStrides: options out of range");
  StridePlan plan;
  plan.options = o;
  plan.feet = feet;

  // Leg geometry: hip pitch to ankle pitch with the knee straight (neutral), ankle above the sole.
  Data data(model);
  const std::string side[2] = {"L_", "R_"};
  const int hip = model.getJointId(side[0] + "hip_pitch");
  const int ankle = model.getJointId(side[0] + "ankle_pitch");
  const int sole0 = model.getFrameId(feet[0]);
  framesForwardKinematics(model, data, neutral(model));
  plan.leg_length = (data.oMi[hip].p - data.oMi[ankle].p).norm();
  const double ankle_height = (data.oMi[ankle].p - data.oMf[sole0].p).norm();
  framesForwardKinematics(model, data, q_stand);
  const Eigen::Vector3d com_stand = centerOfMass(model, data, q_stand);
  framesForwardKinematics(model, data, q_stand);
  const double hip_stand = data.oMi[hip].p.z();
  std::array<Eigen::Vector3d, 2> foot = {data.oMf[model.getFrameId(feet[0])].p,
                                         data.oMf[model.getFrameId(feet[1])].p};
  for (auto& p : foot) p.z() = 0.0;
  double mass = 0.0;
  for (size_t i = 1; i < model.inertias.size(); ++i) mass += model.inertias[i].m;
  plan.mass = mass;

  // CoM height: the hip above the middle of feet stride / 2 apart, legs at leg_reach.
  const double half = 0.25 * o.stride, reach = o.leg_reach * plan.leg_length;
  if (half >= reach) throw std::invalid_argument("planStrides: the legs cannot reach that stride");
  const double hip_needed = ankle_height + std::sqrt(reach * reach - half * half);
  plan.com_drop = std::max(0.0, hip_stand - hip_needed);
  plan.com_height = com_stand.z() - plan.com_drop;
  if (plan.com_height < 0.5 * com_stand.z())
    throw std::invalid_argument("planStrides: the CoM would have to go below half its height");

  // Phases.
  const int steps = o.strides + 2;
  std::vector<Phase> phases;
  auto centre = [](const Eigen::Vector3d& p) { return Eigen::Vector2d(p.x(), p.y()); };
  const Eigen::Vector2d mid0 = 0.5 * (centre(foot[0]) + centre(foot[1]));
  double t = 0.0;
  std::array<Eigen::Vector3d, 2> at = foot;
  // The first double support: from between the feet to the first stance foot (the left one).
  const Eigen::Vector2d roll0(0.5 * o.zmp_travel, 0.0);
  phases.push_back({t, t + o.t_rest, -1, mid0, centre(at[0]) - roll0, {}, {}});
  t += o.t_rest;
  for (int i = 0; i < steps; ++i) {
    const int swing = (i % 2 == 0) ? 1 : 0, stance = 1 - swing;
    const double d = (i == 0 || i == steps - 1) ? 0.5 * o.stride : o.stride;
    const Eigen::Vector3d from = at[swing], to = from + Eigen::Vector3d(d, 0.0, 0.0);
    const Eigen::Vector2d roll(0.5 * o.zmp_travel, 0.0);
    phases.push_back(
        {t, t + o.t_single, swing, centre(at[stance]) - roll, centre(at[stance]) + roll, from, to});
    t += o.t_single;
    at[swing] = to;
    const bool last = i == steps - 1;
    const Eigen::Vector2d next =
        last ? Eigen::Vector2d(0.5 * (centre(at[0]) + centre(at[1]))) : centre(at[swing]);
    const double td = last ? o.t_rest : o.t_double;
    const Eigen::Vector2d arrive = last ? next : Eigen::Vector2d(next - roll);
    phases.push_back({t, t + td, -1, centre(at[stance]) + roll, arrive, {}, {}});
    t += td;
  }
  for (const Phase& p : phases) {
    ContactPhase cp;
    cp.duration = p.t1 - p.t0;
    for (int c = 0; c < 2; ++c)
      if (p.swing != c) cp.contacts.push_back(feet[c]);
    plan.contact_plan.phases.push_back(cp);
  }

  // Samples.
  const int N = static_cast<int>(std::lround(t / o.dt));
  plan.N = N;
  plan.t.resize(N + 1);
  plan.closed.resize(N + 1);
  plan.touchdown.assign(N + 1, 0);
  plan.foot.resize(N + 1);
  plan.zmp_ref.resize(N + 1);
  at = foot;  // footholds, advanced as the swings end
  size_t ph = 0;
  for (int k = 0; k <= N; ++k) {
    const double tk = k * o.dt;
    plan.t[k] = tk;
    while (ph + 1 < phases.size() && tk + 1e-9 >= phases[ph].t1) {
      if (phases[ph].swing >= 0) at[phases[ph].swing] = phases[ph].to;
      ++ph;
    }
    const Phase& p = phases[ph];
    const double s = (tk - p.t0) / (p.t1 - p.t0);
    for (int c = 0; c < 2; ++c) {
      plan.closed[k][c] = p.swing != c;
      plan.foot[k][c] = at[c];
    }
    if (p.swing >= 0) {
      Eigen::Vector3d& f = plan.foot[k][p.swing];
      const double r = std::clamp(s, 0.0, 1.0);
      f = p.from + (p.to - p.from) * (r - std::sin(2.0 * kPi * r) / (2.0 * kPi));
      f.z() = o.swing_height * 0.5 * (1.0 - std::cos(2.0 * kPi * r));
    }
    const Eigen::Vector2d z = p.zmp0 + smoothstep(s) * (p.zmp1 - p.zmp0);
    plan.zmp_ref[k] = Eigen::Vector3d(z.x(), z.y(), 0.0);
    if (k > 0)
      for (int c = 0; c < 2; ++c)
        if (plan.closed[k][c] && !plan.closed[k - 1][c]) plan.touchdown[k] = 1;
  }

  // CoM: cart-table per horizontal axis, constant height.
  const double z_over_g = plan.com_height / kGravity;
  plan.com.assign(N + 1, Eigen::Vector3d::Zero());
  plan.com_acc.assign(N + 1, Eigen::Vector3d::Zero());
  plan.zmp.assign(N + 1, Eigen::Vector3d::Zero());
  for (int axis = 0; axis < 2; ++axis) {
    Eigen::VectorXd p_ref(N + 1);
    for (int k = 0; k <= N; ++k) p_ref[k] = plan.zmp_ref[k][axis];
    // The CoM of the standing robot is not exactly over the middle of the feet: keep its offset.
    const double offset = com_stand[axis] - mid0[axis];
    const Eigen::VectorXd c = cartTable(p_ref, z_over_g, o.dt, o.w_jerk);
    for (int k = 0; k <= N; ++k) plan.com[k][axis] = c[k] + offset;
    for (int k = 1; k < N; ++k)
      plan.com_acc[k][axis] = (c[k + 1] - 2.0 * c[k] + c[k - 1]) / (o.dt * o.dt);
    for (int k = 0; k <= N; ++k) plan.zmp[k][axis] = c[k] - z_over_g * plan.com_acc[k][axis];
  }
  for (int k = 0; k <= N; ++k) plan.com[k].z() = plan.com_height;

  // Forces.
  plan.force.assign(N + 1, {Vector6d::Zero(), Vector6d::Zero()});
  for (int k = 0; k <= N; ++k) {
    const Eigen::Vector3d F = mass * (plan.com_acc[k] + Eigen::Vector3d(0.0, 0.0, kGravity));
    const auto& cl = plan.closed[k];
    if (cl[0] && cl[1]) {
      // Share of the right foot: where the ZMP lies on the segment left → right.
      const Eigen::Vector2d a = centre(plan.foot[k][0]), b = centre(plan.foot[k][1]);
      const Eigen::Vector2d ab = b - a;
      const double alpha = std::clamp(
          (centre(plan.zmp[k]) - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
      plan.force[k][0].head<3>() = (1.0 - alpha) * F;
      plan.force[k][1].head<3>() = alpha * F;
    } else {
      for (int c = 0; c < 2; ++c)
        if (cl[c]) plan.force[k][c].head<3>() = F;
    }
  }
  return plan;
}

}  // namespace stride
