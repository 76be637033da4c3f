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

    Vector6d& ai = data.a_gf[i];
    ai = liMi.actInv(data.a_gf[parent]);
    if constexpr (kHasA) ai += jointMotion(j, a + j.idx_v);
    const Inertia& Y = model.inertias[i];
    if constexpr (kHasV) {
      const Vector6d vJ = jointMotion(j, v + j.idx_v);
      Vector6d& vi = data.v[i];
      vi = liMi.actInv(data.v[parent]) + vJ;
      ai += motionCross(vi, vJ);
      data.f[i] = Y * ai + forceCross(vi, Y * vi);
    } else {
      data.f[i] = Y * ai;
    }
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
