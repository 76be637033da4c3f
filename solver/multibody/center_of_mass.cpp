#include "solver/multibody/center_of_mass.hpp"

#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/kinematics.hpp"

namespace stride {

const Eigen::Vector3d& centerOfMass(const Model& model, Data& data,
                                    const Eigen::Ref<const Eigen::VectorXd>& q) {
  forwardKinematics(model, data, q);
  Eigen::Vector3d h = Eigen::Vector3d::Zero();
  double m = 0;
  for (int i = 1; i < model.njoints(); ++i) {
    const Inertia& Y = model.inertias[i];
    h += Y.m * data.oMi[i].p + data.oMi[i].R * Y.h;
    m += Y.m;
  }
  data.mass = m;
  data.com = m > 0 ? Eigen::Vector3d(h / m) : Eigen::Vector3d::Zero();
  return data.com;
}

const Eigen::Vector3d& centerOfMass(const Model& model, Data& data,
                                    const Eigen::Ref<const Eigen::VectorXd>& q,
                                    const Eigen::Ref<const Eigen::VectorXd>& v) {
  forwardKinematics(model, data, q, v);
  Eigen::Vector3d h = Eigen::Vector3d::Zero(), l = Eigen::Vector3d::Zero();
  double m = 0;
  for (int i = 1; i < model.njoints(); ++i) {
    const Inertia& Y = model.inertias[i];
    h += Y.m * data.oMi[i].p + data.oMi[i].R * Y.h;
    // Linear momentum of body i, rotated to the world: R (m nu - h x w).
    l += data.oMi[i].R * (Y.m * data.v[i].head<3>() - Y.h.cross(data.v[i].tail<3>()));
    m += Y.m;
  }
  data.mass = m;
  data.com = m > 0 ? Eigen::Vector3d(h / m) : Eigen::Vector3d::Zero();
  data.vcom = m > 0 ? Eigen::Vector3d(l / m) : Eigen::Vector3d::Zero();
  return data.com;
}

const Eigen::Matrix3Xd& jacobianCenterOfMass(const Model& model, Data& data,
                                             const Eigen::Ref<const Eigen::VectorXd>& q) {
  // The linear rows of the centroidal momentum matrix are m * Jcom.
  computeCentroidalMap(model, data, q);
  data.Jcom = data.Ag.topRows<3>() / data.mass;
  return data.Jcom;
}

}  // namespace stride
