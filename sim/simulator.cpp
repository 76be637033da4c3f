#include "sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "solver/multibody/cholesky.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/rnea.hpp"

namespace stride::sim {

const char* toString(StepStatus status) {
  switch (status) {
    case StepStatus::Ok:
      return "ok";
    case StepStatus::RejectedTorque:
      return "rejected torque";
    case StepStatus::NonFiniteState:
      return "non-finite state";
    case StepStatus::SingularMassMatrix:
      return "singular mass matrix";
  }
  return "?";
}

double soleFlatFraction(const SimCounters& c) {
  return c.sole_steps > 0
             ? static_cast<double>(c.sole_flat_steps) / static_cast<double>(c.sole_steps)
             : std::numeric_limits<double>::quiet_NaN();
}

std::string footholdText(const SimCounters& c, const SimOptions& o) {
  char text[256];
  int n =
      std::snprintf(text, sizeof text,
                    "%lld footholds (touch-downs), %lld closer than %g cm to an edge of more "
                    "than %g cm, ",
                    static_cast<long long>(c.footholds), static_cast<long long>(c.edge_footholds),
                    100.0 * o.edge_distance, 100.0 * o.edge_rise);
  n = std::max(0, std::min(n, static_cast<int>(sizeof text) - 1));
  if (std::isfinite(c.min_edge_distance))
    n += std::snprintf(text + n, sizeof text - n, "nearest %.3f m", c.min_edge_distance);
  else
    n += std::snprintf(text + n, sizeof text - n, "no edge within %g cm of any",
                       100.0 * o.edge_search_radius);
  n = std::max(0, std::min(n, static_cast<int>(sizeof text) - 1));
  if (c.sole_steps > 0)
    std::snprintf(text + n, sizeof text - n,
                  "; soles down flat (every corner within %g mm) %.1f %% of the time",
                  1000.0 * o.sole_flat_tolerance, 100.0 * soleFlatFraction(c));
  return text;
}

namespace {
void checkOptions(const SimOptions& o) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("Simulator: option " + what);
  };
  if (!(o.dt > 0.0) || !std::isfinite(o.dt)) fail("dt must be positive");
  if (o.substeps < 1) fail("substeps must be >= 1");
  if (!(o.friction >= 0.0) || !std::isfinite(o.friction)) fail("friction must be >= 0");
  if (!(o.contact_margin >= 0.0)) fail("contact_margin must be >= 0");
  if (!(o.penetration_gain >= 0.0 && o.penetration_gain <= 1.0))
    fail("penetration_gain must be in [0, 1]");
  if (!(o.penetration_slop >= 0.0)) fail("penetration_slop must be >= 0");
  if (!(o.max_correction_velocity >= 0.0)) fail("max_correction_velocity must be >= 0");
  if (o.pgs_max_iterations < 1) fail("pgs_max_iterations must be >= 1");
  if (!(o.pgs_tolerance >= 0.0)) fail("pgs_tolerance must be >= 0");
  if (!(o.regularization >= 0.0)) fail("regularization must be >= 0");
  if (!std::isfinite(o.ground_height)) fail("ground_height must be finite");
  if (!(o.max_velocity > 0.0)) fail("max_velocity must be > 0");
  if (!(o.foothold_lift >= 0.0) || !std::isfinite(o.foothold_lift))
    fail("foothold_lift must be >= 0");
  if (!(o.edge_rise >= 0.0) || !std::isfinite(o.edge_rise)) fail("edge_rise must be >= 0");
  if (!(o.edge_distance >= 0.0) || !std::isfinite(o.edge_distance))
    fail("edge_distance must be >= 0");
  if (!(o.edge_search_radius >= o.edge_distance) || !std::isfinite(o.edge_search_radius))
    fail("edge_search_radius must be >= edge_distance");
}
}  // namespace

Simulator::Simulator(const Model& model, std::vector<ContactPoint> points,
                     const SimOptions& options)
    : model_(model),
      options_(options),
      points_(std::move(points)),
      terrain_(options.terrain ? *options.terrain : terrain::Terrain(options.ground_height)),
      data_(model_) {
  checkOptions(options_);
  for (const ContactPoint& p : points_)
    if (p.frame < 0 || p.frame >= model_.nframes() || !p.offset.allFinite())
      throw std::invalid_argument("Simulator: contact point '" + p.name + "' is invalid");
  tau_first_ = model_.hasFreeFlyer() ? 6 : 0;
  nu_ = model_.nv - tau_first_;

  const int nv = model_.nv, np = static_cast<int>(points_.size());
  q_ = neutral(model_);
  v_.setZero(nv);
  tau_applied_.setZero(nu_);
  rhs_.setZero(nv);
  v_free_.setZero(nv);
  q_prev_ = q_;
  // Every constraint slot of every point may be active at once (ground_contact.hpp).
  const int ns = kConstraintsPerPoint * np;
  geometry_.resize(np, nv);
  active_.assign(ns, 0);
  Jc_.setZero(3 * ns, nv);
  MinvJt_.setZero(nv, 3 * ns);
  G_.setZero(3 * ns, 3 * ns);
  c_.setZero(3 * ns);
  p_.setZero(3 * ns);
  warm_.setZero(3, ns);
  impulse_sum_.setZero(3, np);
  forces_.setZero(3, np);
  contacts_.assign(np, PointContact{});
  on_wall_.assign(np, 0);
  touching_wall_.assign(np, 0);
  swung_.assign(np, 1);
  touching_support_.assign(np, 0);
  // A contact's points are consecutive (contactPointsFromRobot).
  for (int i = 0; i < np;) {
    int n = 1;
    while (i + n < np && points_[i + n].contact == points_[i].contact) ++n;
    if (n > 1) soles_.emplace_back(i, n);
    i += n;
  }
}

Simulator::Simulator(const Robot& robot, const SimOptions& options)
    : Simulator(robot.model, contactPointsFromRobot(robot), options) {
  reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
}

void Simulator::reset(const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, double time) {
  model_.checkConfiguration(q, "q");
  model_.checkVelocity(v, "v");
  if (!q.allFinite() || !v.allFinite() || !std::isfinite(time))
    throw std::invalid_argument("Simulator::reset: non-finite state or time");
  q_ = q;
  normalize(model_, q_);
  v_ = v;
  time_ = time;
  wrench_until_ = -1.0;
  warm_.setZero();
  forces_.setZero();
  for (PointContact& c : contacts_) c = PointContact{};
  std::fill(on_wall_.begin(), on_wall_.end(), 0);
  std::fill(swung_.begin(), swung_.end(), 1);  // the points standing now are footholds
  last_status_ = StepStatus::Ok;
}

void Simulator::applyExternalWrench(const Vector6d& wrench_world_on_base, double until_time) {
  if (!model_.hasFreeFlyer())
    throw std::invalid_argument("Simulator::applyExternalWrench: the robot has no floating base");
  if (!wrench_world_on_base.allFinite())
    throw std::invalid_argument("Simulator::applyExternalWrench: non-finite wrench");
  wrench_ = wrench_world_on_base;
  wrench_until_ = until_time;
}

double Simulator::normalForce(int contact) const {
  double sum = 0.0;
  for (size_t i = 0; i < points_.size(); ++i)
    if (points_[i].contact == contact) sum += forces_(2, static_cast<Eigen::Index>(i));
  return sum;
}

double Simulator::kineticEnergy() {
  crba(model_, data_, q_);
  return 0.5 * v_.dot(data_.M * v_);
}

StepStatus Simulator::step(const Eigen::Ref<const Eigen::VectorXd>& tau) {
  if (tau.size() != nu_) throwSizeError("Simulator::step", "tau", nu_, tau.size());
  StepStatus status = StepStatus::Ok;
  if (!tau.allFinite()) {
    // A NaN torque would poison the state for good: apply none and say so.
    tau_applied_.setZero();
    status = StepStatus::RejectedTorque;
    ++counters_.rejected_torques;
  } else {
    tau_applied_ = tau;
    if (options_.clamp_torques) {
      bool clamped = false;
      for (int i = 0; i < nu_; ++i) {
        const double limit = model_.effortLimit[tau_first_ + i];
        if (!(limit >= 0.0) || std::isinf(limit)) continue;  // no limit given
        const double t = std::clamp(tau_applied_[i], -limit, limit);
        clamped |= t != tau_applied_[i];
        tau_applied_[i] = t;
      }
      if (clamped) ++counters_.clamped_steps;
    }
  }

  impulse_sum_.setZero();
  const double h = options_.dt / options_.substeps;
  for (int s = 0; s < options_.substeps; ++s) {
    const StepStatus sub = substep(h);
    if (sub != StepStatus::Ok) {
      status = sub;
      if (sub == StepStatus::SingularMassMatrix) break;
    }
  }
  forces_ = impulse_sum_ / options_.dt;
  for (size_t i = 0; i < contacts_.size(); ++i)
    contacts_[i].force = forces_.col(static_cast<Eigen::Index>(i));
  ++counters_.steps;
  last_status_ = status;
  return status;
}

StepStatus Simulator::substep(double h) {
  const int np = static_cast<int>(points_.size());
  // Dynamics without contact: M, its factorization and b(q, v) share one placement sweep.
  crba(model_, data_, q_);
  if (!factorizeMassMatrix(model_, data_)) {
    ++counters_.nonfinite_states;
    return StepStatus::SingularMassMatrix;
  }
  nonLinearEffectsFromKinematics(model_, data_, v_);
  rhs_ = -data_.nle;
  rhs_.tail(nu_) += tau_applied_;
  if (time_ < wrench_until_) {
    // World wrench at the base origin -> generalized force on the base's local velocity:
    // power f·(R ν) + n·(R ω) gives [Rᵀ f; Rᵀ n].
    const Eigen::Matrix3d& R = data_.oMi[1].R;
    rhs_.head<3>().noalias() += R.transpose() * wrench_.head<3>();
    rhs_.segment<3>(3).noalias() += R.transpose() * wrench_.tail<3>();
  }
  solveMassMatrix(model_, data_, rhs_);
  v_free_ = v_ + h * rhs_;

  // Detection from geometry. A constraint is a candidate when its point is within the margin of
  // the surface or would reach it during this substep at its contact-free velocity (so a fast fall
  // cannot step over the margin and land deep inside).
  updateContactGeometry(model_, data_, points_, terrain_, v_free_, options_.contact_margin, h,
                        geometry_);
  int na = 0;
  for (int i = 0; i < np; ++i) {
    bool candidate = false;
    for (int k = 0; k < geometry_.count[i]; ++k) {
      const int slot = kConstraintsPerPoint * i + k;
      const double vn = geometry_.Jc.row(3 * slot + 2).dot(v_free_);
      const double reach = options_.contact_margin + h * std::max(0.0, -vn);
      if (geometry_.constraint[slot].distance < reach) {
        active_[na++] = slot;
        candidate = true;
      }
    }
    contacts_[i].candidate = candidate;
    contacts_[i].in_contact = false;
    contacts_[i].height = geometry_.height(i);
  }

  v_ = v_free_;
  if (na > 0) {
    counters_.last_pgs_iterations = solveContacts(h, na);
    if (counters_.last_pgs_iterations > options_.pgs_max_iterations) {
      counters_.last_pgs_iterations = options_.pgs_max_iterations;
      ++counters_.pgs_unconverged;
    }
    const int m = 3 * na;
    v_.noalias() += MinvJt_.leftCols(m) * p_.head(m);
  }
  // Constraints that left the candidate set start from zero when they come back.
  warm_.setZero();
  for (int i = 0; i < np; ++i) touching_wall_[i] = touching_support_[i] = 0;
  for (int a = 0; a < na; ++a) {
    const int slot = active_[a];
    const int i = slot / kConstraintsPerPoint;
    const Eigen::Vector3d impulse = p_.segment<3>(3 * a);
    warm_.col(slot) = impulse;
    const terrain::Contact& c = geometry_.constraint[slot];
    // Forces are reported in world axes: the impulse in the constraint's frame [t1 t2 n] turned.
    if (c.world_axes)
      impulse_sum_.col(i) += impulse;
    else
      impulse_sum_.col(i) += impulse.x() * c.t1 + impulse.y() * c.t2 + impulse.z() * c.normal;
    if (impulse.z() > 0.0) {
      contacts_[i].in_contact = true;
      if (c.kind == terrain::Contact::Kind::Wall) touching_wall_[i] = 1;
      if (slot % kConstraintsPerPoint == 0) touching_support_[i] = 1;
    }
  }
  // A trip: a point that starts pushing on a vertical face (a riser, a box's side).
  for (int i = 0; i < np; ++i) {
    if (touching_wall_[i] && !on_wall_[i]) ++counters_.trips;
    on_wall_[i] = touching_wall_[i];
  }
  // A touch-down: a point that starts loading its support after a swing. Its place on the support
  // (the point under it on flat ground) is measured against the true terrain's edges.
  for (int i = 0; i < np; ++i) {
    if (!touching_support_[i]) {
      if (contacts_[i].height > options_.foothold_lift) swung_[i] = 1;
    } else if (swung_[i]) {
      swung_[i] = 0;
      ++counters_.footholds;
      const Eigen::Vector3d& at = geometry_.constraint[kConstraintsPerPoint * i].point;
      const double d =
          terrain_.edgeDistance(at.x(), at.y(), options_.edge_rise, options_.edge_search_radius);
      counters_.min_edge_distance = std::min(counters_.min_edge_distance, d);
      if (d < options_.edge_distance) ++counters_.edge_footholds;
    }
  }
  // A sole down (a corner loading its support) is flat when every corner is within
  // sole_flat_tolerance of the terrain under it: not "every corner loaded", since a sole flat on
  // the ground often carries its load on three corners, the fourth touching with none.
  for (const auto& [first, n] : soles_) {
    bool down = false, flat = true;
    for (int i = first; i < first + n; ++i) {
      down = down || touching_support_[i];
      flat = flat && std::abs(contacts_[i].height) <= options_.sole_flat_tolerance;
    }
    if (!down) continue;
    ++counters_.sole_steps;
    if (flat) ++counters_.sole_flat_steps;
  }

  // q⁺ = q ⊕ h v⁺ (rhs_ is free again: it holds h v⁺).
  q_prev_ = q_;
  rhs_ = h * v_;
  integrate(model_, q_prev_, rhs_, q_);
  // A velocity no robot reaches (1000 rad/s or m/s by default) is not physics any more: joints
  // spun up in the air by full torque with nothing to stop them (the mock robot has no joint
  // velocity limits yet), or an impact at such speeds. Held and reported like a non-finite state.
  if (!q_.allFinite() || !(v_.cwiseAbs().maxCoeff() <= options_.max_velocity)) {
    q_ = q_prev_;
    v_.setZero();
    warm_.setZero();
    ++counters_.nonfinite_states;
    return StepStatus::NonFiniteState;
  }
  time_ += h;
  return StepStatus::Ok;
}

// Projected Gauss-Seidel over the active points. Returns the number of sweeps run, or
// pgs_max_iterations + 1 when it stopped without converging.
int Simulator::solveContacts(double h, int na) {
  const int m = 3 * na;
  auto J = Jc_.topRows(m);
  for (int a = 0; a < na; ++a) J.middleRows<3>(3 * a) = geometry_.Jc.middleRows<3>(3 * active_[a]);
  // M⁻¹ Jᵀ through the tree-sparse LᵀDL of M (no inverse formed), then G = J M⁻¹ Jᵀ.
  auto MinvJt = MinvJt_.leftCols(m);
  MinvJt = J.transpose();
  solveMassMatrixRows(model_, data_, MinvJt);
  auto G = G_.topLeftCorner(m, m);
  G.noalias() = J * MinvJt;

  // Contact velocity without impulses, minus the velocity each constraint must reach.
  auto c = c_.head(m);
  c.noalias() = J * v_free_;
  for (int a = 0; a < na; ++a) {
    const double height = geometry_.constraint[active_[a]].distance;
    double target;
    if (height >= 0.0) {
      // Above the ground: may approach by the remaining gap within this substep, no further.
      target = -height / h;
    } else {
      // Inside: pushed out by a fraction of the depth beyond the slop (Baumgarte on position).
      const double excess = std::max(0.0, -height - options_.penetration_slop);
      target = std::min(options_.penetration_gain * excess / h, options_.max_correction_velocity);
    }
    c[3 * a + 2] -= target;
    const double reg = options_.regularization * G.block<3, 3>(3 * a, 3 * a).trace() / 3.0;
    for (int k = 0; k < 3; ++k) G(3 * a + k, 3 * a + k) += reg;
  }

  auto p = p_.head(m);
  for (int a = 0; a < na; ++a) p.segment<3>(3 * a) = warm_.col(active_[a]);

  const double mu = options_.friction;
  for (int it = 1; it <= options_.pgs_max_iterations; ++it) {
    double max_dp = 0.0, max_p = 0.0;
    for (int a = 0; a < na; ++a) {
      // Residual velocity of point a with the current impulses (G symmetric: read columns).
      Eigen::Vector3d r = c.segment<3>(3 * a);
      r.noalias() += G.middleCols<3>(3 * a).transpose() * p;
      const Eigen::Matrix3d Ga = G.block<3, 3>(3 * a, 3 * a);
      const Eigen::Vector3d old = p.segment<3>(3 * a);
      // Normal: the impulse that zeroes the normal residual, kept non-negative.
      const double pn = std::max(0.0, old.z() - r.z() / Ga(2, 2));
      // Tangent: a step against the sliding velocity (given the new normal impulse), projected
      // radially on the disk |p_t| <= μ p_n. The step is the scalar 1/λmax(G_tt), not G_tt⁻¹:
      // at the fixed point on the cone's edge, p_t − r_t/λ ∥ p_t then makes the sliding velocity
      // r_t exactly opposite to p_t (maximal dissipation); a G_tt⁻¹ step would tilt the friction
      // away from the sliding direction wherever G_tt is not isotropic (any point off the centre
      // of mass).
      const Eigen::Vector2d rt = r.head<2>() + Ga.block<2, 1>(0, 2) * (pn - old.z());
      const double half_sum = 0.5 * (Ga(0, 0) + Ga(1, 1)), half_diff = 0.5 * (Ga(0, 0) - Ga(1, 1));
      const double lambda_max = half_sum + std::sqrt(half_diff * half_diff + Ga(0, 1) * Ga(1, 0));
      Eigen::Vector2d pt = old.head<2>() - rt / lambda_max;
      const double limit = mu * pn, norm = pt.norm();
      if (norm > limit) pt *= norm > 0.0 ? limit / norm : 0.0;
      const Eigen::Vector3d updated(pt.x(), pt.y(), pn);
      max_dp = std::max(max_dp, (updated - old).cwiseAbs().maxCoeff());
      max_p = std::max(max_p, updated.cwiseAbs().maxCoeff());
      p.segment<3>(3 * a) = updated;
    }
    if (max_dp <= options_.pgs_tolerance * max_p) return it;
  }
  return options_.pgs_max_iterations + 1;
}

}  // namespace stride::sim
