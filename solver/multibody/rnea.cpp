#include "solver/multibody/rnea.hpp"

#include "solver/multibody/joint.hpp"

namespace stride {

namespace {

// The shared sweeps. kHasV / kHasA skip the velocity and acceleration terms at compile time;
// kReuse reads the placements already in data.liMi instead of computing them from q (null then).
template <bool kHasV, bool kHasA, bool kReuse = false>
void rneaSweeps(const Model& model, Data& data, const double* q, const double* v, const double* a,
                Eigen::VectorXd& tau) {
  data.v[0].setZero();
  data.a_gf[0].head<3>() = -model.gravity;
  data.a_gf[0].tail<3>().setZero();
  const int n = model.njoints();
  for (int i = 1; i < n; ++i) {
    const Joint& j = model.joints[i];
    const int parent = j.parent;
    SE3& liMi = data.liMi[i];
    if constexpr (!kReuse) {
      jointPlacement(j, q + j.idx_q, liMi);
      data.oMi[i] = data.oMi[parent] * liMi;
    }

    // In 3-vector halves [linear; angular]: sums of 6-vector temporaries store their halves to
    // the stack and reload them whole, stalling on store forwarding.
    const Eigen::Matrix3d& R = liMi.R;
    const Eigen::Vector3d& p = liMi.p;
    // X^-1 m = [R^T (m_l - p x m_a); R^T m_a]
    const Vector6d& apar = data.a_gf[parent];
    Eigen::Vector3d a_a = R.transpose() * apar.tail<3>();
    Eigen::Vector3d a_l = R.transpose() * (apar.head<3>() - p.cross(apar.tail<3>()));
    if constexpr (kHasA) {
      const Vector6d aJ = jointMotion(j, a + j.idx_v);
      a_l += aJ.head<3>();
      a_a += aJ.tail<3>();
    }
    const Inertia& Y = model.inertias[i];
    if constexpr (kHasV) {
      const Vector6d vJ = jointMotion(j, v + j.idx_v);
      const Eigen::Vector3d j_l = vJ.head<3>(), j_a = vJ.tail<3>();
      const Vector6d& vpar = data.v[parent];
      const Eigen::Vector3d v_a = R.transpose() * vpar.tail<3>() + j_a;
      const Eigen::Vector3d v_l = R.transpose() * (vpar.head<3>() - p.cross(vpar.tail<3>())) + j_l;
      data.v[i].head<3>() = v_l;
      data.v[i].tail<3>() = v_a;
      // a += v x vJ;  f = Y a + v x* (Y v)
      a_l += v_a.cross(j_l) + v_l.cross(j_a);
      a_a += v_a.cross(j_a);
      const Eigen::Vector3d h_l = Y.m * v_l - Y.h.cross(v_a);
      const Eigen::Vector3d h_a = Y.I * v_a + Y.h.cross(v_l);
      data.f[i].head<3>() = Y.m * a_l - Y.h.cross(a_a) + v_a.cross(h_l);
      data.f[i].tail<3>() = Y.I * a_a + Y.h.cross(a_l) + v_a.cross(h_a) + v_l.cross(h_l);
    } else {
      data.f[i].head<3>() = Y.m * a_l - Y.h.cross(a_a);
      data.f[i].tail<3>() = Y.I * a_a + Y.h.cross(a_l);
    }
    data.a_gf[i].head<3>() = a_l;
    data.a_gf[i].tail<3>() = a_a;
  }
  for (int i = n - 1; i > 0; --i) {
    const Joint& j = model.joints[i];
    jointForceProjection(j, data.f[i], tau.data() + j.idx_v);
    if (j.parent > 0) data.f[j.parent] += data.liMi[i].actForce(data.f[i]);
  }
}

}  // namespace

const Eigen::VectorXd& rnea(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& v,
                            const Eigen::Ref<const Eigen::VectorXd>& a) {
  model.checkConfiguration(q, "rnea");
  model.checkVelocity(v, "rnea");
  if (a.size() != model.nv) throwSizeError("rnea", "a", model.nv, a.size());
  rneaSweeps<true, true>(model, data, q.data(), v.data(), a.data(), data.tau);
  return data.tau;
}

const Eigen::VectorXd& nonLinearEffects(const Model& model, Data& data,
                                        const Eigen::Ref<const Eigen::VectorXd>& q,
                                        const Eigen::Ref<const Eigen::VectorXd>& v) {
  model.checkConfiguration(q, "nonLinearEffects");
  model.checkVelocity(v, "nonLinearEffects");
  rneaSweeps<true, false>(model, data, q.data(), v.data(), nullptr, data.nle);
  return data.nle;
}

const Eigen::VectorXd& nonLinearEffectsFromKinematics(const Model& model, Data& data,
                                                      const Eigen::Ref<const Eigen::VectorXd>& v) {
  model.checkVelocity(v, "nonLinearEffectsFromKinematics");
  rneaSweeps<true, false, true>(model, data, nullptr, v.data(), nullptr, data.nle);
  return data.nle;
}

const Eigen::VectorXd& computeGeneralizedGravity(const Model& model, Data& data,
                                                 const Eigen::Ref<const Eigen::VectorXd>& q) {
  model.checkConfiguration(q, "computeGeneralizedGravity");
  rneaSweeps<false, false>(model, data, q.data(), nullptr, nullptr, data.g);
  return data.g;
}

}  // namespace stride
