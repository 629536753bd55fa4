// Recursive Newton-Euler: inverse dynamics tau = M(q) a + C(q, v) v + g(q) - sum J^T fext,
// and its special cases (nonlinear effects, generalised gravity).
#pragma once

#include <vector>

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/joint.hpp"
#include "robodiff/dynamics/kinematics.hpp"

namespace robodiff {

// The acceleration that stands for gravity at the root (a_0 = -g), in the world frame.
template <class S> Motion<S> gravityAcceleration(const Model& model) {
  Motion<S> a0;
  a0.linear = -asScalar<S>(model.gravity);
  return a0;
}

namespace detail {

// The backward pass shared by rnea and gravity: tau = S^T f, f_parent += liMi * f.
template <class S> void rneaBackward(const Model& model, Data<S>& data) {
  for (int j = model.njoints() - 1; j >= 0; --j) {
    const Joint& joint = model.joints[j];
    for (int k = 0; k < joint.nv; ++k) data.tau[joint.idx_v + k] = projectForce<S>(joint, data.f[j], k);
    if (joint.parent >= 0) data.f[joint.parent] += data.liMi[j].act(data.f[j]);
  }
}

}  // namespace detail

// tau = RNEA(q, v, a). fext (optional, one per joint) are external forces acting on each
// joint's body, expressed in that joint's frame. Result in data.tau.
template <class S, class Q, class V, class A>
const VecX<S>& rnea(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q, const Eigen::MatrixBase<V>& v,
                    const Eigen::MatrixBase<A>& a, const std::vector<Force<S>>* fext = nullptr) {
  detail::accelerationPass(model, data, q, v, a, gravityAcceleration<S>(model));
  for (int j = 0; j < model.njoints(); ++j) {
    const auto& I = asScalar<S>(model.bodies[j]);
    data.f[j] = I.dynamicForce(data.v[j], data.a[j]);
    if (fext) data.f[j] -= (*fext)[j];
  }
  detail::rneaBackward(model, data);
  return data.tau;
}

// Coriolis, centrifugal and gravity terms: RNEA(q, v, 0).
template <class S, class Q, class V>
const VecX<S>& nonLinearEffects(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q,
                                const Eigen::MatrixBase<V>& v) {
  return rnea(model, data, q, v, VecX<S>::Zero(model.nv));
}

// Generalised gravity g(q) = RNEA(q, 0, 0), without the velocity terms.
template <class S, class Q>
const VecX<S>& computeGeneralizedGravity(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  const Motion<S> a0 = gravityAcceleration<S>(model);
  for (int j = 0; j < model.njoints(); ++j) {
    const Joint& joint = model.joints[j];
    const int p = joint.parent;
    data.liMi[j] = jointPlacement<S>(joint, q);
    data.oMi[j] = p >= 0 ? data.oMi[p] * data.liMi[j] : data.liMi[j];
    data.a[j] = data.liMi[j].actInv(p >= 0 ? data.a[p] : a0);
    data.f[j] = asScalar<S>(model.bodies[j]) * data.a[j];
  }
  detail::rneaBackward(model, data);
  return data.tau;
}

}  // namespace robodiff
