#include "solver/multibody/centroidal.hpp"

#include "solver/multibody/crba.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/kinematics.hpp"

namespace stride {

const Vector6d& computeCentroidalMomentum(const Model& model, Data& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& q,
                                          const Eigen::Ref<const Eigen::VectorXd>& v) {
  forwardKinematics(model, data, q, v);
  // Sum the bodies' momenta about the world origin, then move the moment to the CoM.
  Vector6d h = Vector6d::Zero();
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
  double m = 0;
  for (int i = 1; i < model.njoints(); ++i) {
    const Inertia& Y = model.inertias[i];
    h += data.oMi[i].actForce(Y * data.v[i]);
    first_moment += Y.m * data.oMi[i].p + data.oMi[i].R * Y.h;
    m += Y.m;
  }
  data.mass = m;
  data.com = m > 0 ? Eigen::Vector3d(first_moment / m) : Eigen::Vector3d::Zero();
  data.vcom = m > 0 ? Eigen::Vector3d(h.head<3>() / m) : Eigen::Vector3d::Zero();
  data.hg.head<3>() = h.head<3>();
  data.hg.tail<3>() = h.tail<3>() - data.com.cross(h.head<3>());
  return data.hg;
}

const Matrix6Xd& computeCentroidalMap(const Model& model, Data& data,
                                      const Eigen::Ref<const Eigen::VectorXd>& q) {
  forwardKinematics(model, data, q);
  updateJointJacobians(model, data);
  compositeInertiaSweep(model, data, &data.Ag);
  // oYcrb[0] now holds the whole robot: its first moment gives the CoM.
  const Inertia& Yall = data.oYcrb[0];
  data.mass = Yall.m;
  data.com = Yall.com();
  // Columns are momenta about the world origin; shift the moments to the CoM.
  for (int k = 0; k < model.nv; ++k)
    data.Ag.col(k).tail<3>() -= data.com.cross(Eigen::Vector3d(data.Ag.col(k).head<3>()));
  return data.Ag;
}

}  // namespace stride
