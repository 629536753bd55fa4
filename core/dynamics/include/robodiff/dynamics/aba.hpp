// Articulated Body Algorithm: forward dynamics ddq = ABA(q, v, tau), in O(n), with
// articulated inertias in the joint frames (Featherstone, as in Pinocchio).
#pragma once

#include <vector>

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/joint.hpp"
#include "robodiff/dynamics/kinematics.hpp"
#include "robodiff/dynamics/rnea.hpp"
#include "robodiff/dynamics/spd_inverse.hpp"

namespace robodiff {

// ia - udinv u^T, the articulated inertia a joint hands its parent, for a symmetric ia
// (udinv = U D^-1): computed on and below the diagonal and mirrored, so that a traced
// result holds each entry once (the full product is 15 entries and 30 operations more).
template <class S>
Mat6<S> articulatedUpdate(const Mat6<S>& ia, const JointBlock<S>& udinv, const JointBlock<S>& u) {
  Mat6<S> out;
  for (int c = 0; c < 6; ++c)
    for (int r = c; r < 6; ++r) out(r, c) = out(c, r) = ia(r, c) - udinv.row(r).dot(u.row(c));
  return out;
}

template <class S, class Q, class V, class T>
const VecX<S>& aba(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q, const Eigen::MatrixBase<V>& v,
                   const Eigen::MatrixBase<T>& tau, const std::vector<Force<S>>* fext = nullptr) {
  const int n = model.njoints();
  // Pass 1, root to leaves: kinematics, bias accelerations and forces.
  forwardKinematics(model, data, q, v);
  for (int j = 0; j < n; ++j) {
    data.c[j] = data.v[j].cross(jointMotion<S>(model.joints[j], v));
    const auto& I = asScalar<S>(model.bodies[j]);
    data.Ia[j] = I.matrix();
    data.pA[j] = I.dynamicForce(data.v[j], Motion<S>::Zero());  // v x* (I v)
    if (fext) data.pA[j] -= (*fext)[j];
  }
  // Pass 2, leaves to root: articulated inertias and bias forces.
  for (int j = n - 1; j >= 0; --j) {
    const Joint& joint = model.joints[j];
    data.U[j] = rightMultiplySubspace(joint, data.Ia[j]);
    JointSquare<S>& D = data.D[j];
    for (int k = 0; k < joint.nv; ++k) D.row(k) = projectVector<S>(joint, data.U[j].col(k)).transpose();
    // A multi-DoF root (a free-flyer's 6 x 6) is solved with D in pass 3; every other
    // joint needs D^-1 for the update of its parent's inertia.
    if (joint.parent >= 0 || joint.nv == 1) data.Dinv[j] = inverseSymmetricPositiveDefinite<S>(D);
    JointVector<S> pAproj = projectVector<S>(joint, data.pA[j].toVector());
    for (int k = 0; k < joint.nv; ++k) data.u[j][k] = tau[joint.idx_v + k] - pAproj[k];
    if (joint.parent >= 0) {
      JointBlock<S> UDinv = data.U[j] * data.Dinv[j];
      const Mat6<S> Ia = articulatedUpdate(data.Ia[j], UDinv, data.U[j]);
      Vec6<S> pa = data.pA[j].toVector() + Ia * data.c[j].toVector() + UDinv * data.u[j];
      data.Ia[joint.parent] += data.liMi[j].actOnSymmetric(Ia);
      data.pA[joint.parent] += data.liMi[j].act(Force<S>::fromVector(pa));
    }
  }
  // Pass 3, root to leaves: accelerations.
  const Motion<S> a0 = gravityAcceleration<S>(model);
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    const int p = joint.parent;
    data.a[j] = data.liMi[j].actInv(p >= 0 ? data.a[p] : a0) + data.c[j];
    const JointVector<S> rhs = data.u[j] - data.U[j].transpose() * data.a[j].toVector();
    const JointVector<S> qdd = p < 0 && joint.nv > 1 ? solveSymmetricPositiveDefinite<S>(data.D[j], rhs)
                                                      : JointVector<S>(data.Dinv[j] * rhs);
    for (int k = 0; k < joint.nv; ++k) data.ddq[joint.idx_v + k] = qdd[k];
    data.a[j] += jointMotion<S>(joint, data.ddq);
  }
  return data.ddq;
}

}  // namespace robodiff
