#include "sim/ground_contact.hpp"

#include <stdexcept>

namespace stride::sim {

std::vector<ContactPoint> contactPointsFromRobot(const Robot& robot) {
  const Model& model = robot.model;
  std::vector<ContactPoint> points;
  for (size_t c = 0; c < robot.contacts.size(); ++c) {
    const ContactSpec& spec = robot.contacts[c];
    const int frame = model.getFrameId(spec.frame);
    if (spec.dim == 3) {
      points.push_back({spec.frame, frame, Eigen::Vector3d::Zero(), static_cast<int>(c)});
      continue;
    }
    const double hx = robot.sole_half_extents.x(), hy = robot.sole_half_extents.y();
    if (!(hx > 0.0) || !(hy > 0.0))
      throw std::invalid_argument("contactPointsFromRobot: surface contact '" + spec.frame +
                                  "' of robot '" + robot.name + "' needs sole_half_extents");
    // Corners in a fixed order (front-left, front-right, back-left, back-right in the sole frame).
    const struct {
      const char* name;
      double sx, sy;
    } corners[] = {{"fl", 1, 1}, {"fr", 1, -1}, {"bl", -1, 1}, {"br", -1, -1}};
    for (const auto& k : corners)
      points.push_back({spec.frame + "/" + k.name, frame, Eigen::Vector3d(k.sx * hx, k.sy * hy, 0),
                        static_cast<int>(c)});
  }
  return points;
}

void ContactGeometry::resize(int points, int nv) {
  position.setZero(3, points);
  J.setZero(3 * points, nv);
  count.assign(points, 1);
  constraint.assign(static_cast<std::size_t>(kConstraintsPerPoint) * points, terrain::Contact{});
  Jc.setZero(3 * kConstraintsPerPoint * points, nv);
}

void updateContactGeometry(const Model& model, const Data& data,
                           const std::vector<ContactPoint>& points, const terrain::Terrain& terrain,
                           const Eigen::VectorXd& v, double margin, double h,
                           ContactGeometry& geometry) {
  // Two passes: the points' places and Jacobians first, in exactly the loop the flat ground had
  // (GCC contracts `nu + w.cross(p)` into FMAs differently when the terrain's queries share the
  // loop: 1-ulp differences in J, and a flat terrain would no longer give the plain ground's bits:
  // tests/sim/test_terrain_contact.cpp), then the terrain's constraints.
  for (size_t i = 0; i < points.size(); ++i) {
    const ContactPoint& pt = points[i];
    const Frame& frame = model.frames[pt.frame];
    const SE3& oMj = data.oMi[frame.parentJoint];
    // The point in the parent joint's frame, then in the world.
    const Eigen::Vector3d p_joint = frame.placement.R * pt.offset + frame.placement.p;
    const Eigen::Vector3d p = oMj.R * p_joint + oMj.p;
    geometry.position.col(i) = p;
    // data.J holds world-frame motion subspaces [velocity of the point at the world origin; w]:
    // the velocity of the point p is nu_o + w x p.
    const int row = 3 * static_cast<int>(i);
    if (frame.parentJoint == 0) continue;
    const Joint& jt = model.joints[frame.parentJoint];
    for (int k = jt.idx_v + jt.nv - 1; k >= 0; k = model.parentDof[k]) {
      const Eigen::Vector3d nu = data.J.col(k).head<3>(), w = data.J.col(k).tail<3>();
      geometry.J.block<3, 1>(row, k) = nu + w.cross(p);
    }
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const int row = 3 * static_cast<int>(i);
    const Eigen::Vector3d p = geometry.position.col(i);
    // Faces are looked for as far as the point can travel in this step, and the margin.
    const double speed = (geometry.J.middleRows<3>(row) * v).norm();
    const int slot0 = kConstraintsPerPoint * static_cast<int>(i);
    const int n =
        terrain.contacts(p, margin + h * speed, &geometry.constraint[slot0], kConstraintsPerPoint);
    geometry.count[i] = n;
    for (int k = 0; k < n; ++k) {
      const terrain::Contact& c = geometry.constraint[slot0 + k];
      auto rows = geometry.Jc.middleRows<3>(3 * (slot0 + k));
      if (c.world_axes) {
        rows = geometry.J.middleRows<3>(row);  // the flat ground's frame: the same bits as before
      } else {
        rows.row(0).noalias() = c.t1.transpose() * geometry.J.middleRows<3>(row);
        rows.row(1).noalias() = c.t2.transpose() * geometry.J.middleRows<3>(row);
        rows.row(2).noalias() = c.normal.transpose() * geometry.J.middleRows<3>(row);
      }
    }
  }
}

}  // namespace stride::sim
