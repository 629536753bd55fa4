// Composite Rigid Body Algorithm: the joint-space mass matrix M(q), full and symmetric.
//
// Works in the world frame (as Pinocchio does): composite inertias are then plain sums
// of the bodies' linearly parametrised inertias, and M(i, j) = J_i^T (Y_j J_j) for every
// joint i supporting joint j. Entries of joints on different branches stay zero.
#pragma once

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/joint.hpp"

namespace robodiff {

// The body inertia (given in its joint frame) in the world frame, linearly parametrised.
template <class S> InertiaSum<S> worldInertia(const Inertia<double>& body, const SE3<S>& oMi) {
  const auto& I = asScalar<S>(body);
  const Mat3<S>& R = oMi.rotation;
  InertiaSum<S> out;
  out.mass = I.mass;
  const Vec3<S> c = oMi.act(I.lever);
  out.h = I.mass * c;
  // R I R^T (symmetric: upper triangle, then mirrored) + m (|c|^2 1 - c c^T).
  const Mat3<S> RI = R * I.inertia;
  const S cc = c.squaredNorm();
  for (int r = 0; r < 3; ++r)
    for (int k = r; k < 3; ++k) {
      S value = RI.row(r).dot(R.row(k)) - I.mass * (c[r] * c[k]);
      if (r == k) value += I.mass * cc;
      out.rotational(r, k) = value;
      out.rotational(k, r) = value;
    }
  return out;
}

template <class S, class Q> const MatX<S>& crba(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  const int n = model.njoints();
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    data.liMi[j] = jointPlacement<S>(joint, q);
    data.oMi[j] = joint.parent >= 0 ? data.oMi[joint.parent] * data.liMi[j] : data.liMi[j];
    for (int k = 0; k < joint.nv; ++k) data.J.col(joint.idx_v + k) = worldSubspaceColumn(joint, data.oMi[j], k);
    data.oYcrb[j] = worldInertia(model.bodies[j], data.oMi[j]);
  }
  // Leaves to root. When joint j is reached its composite inertia is complete, and the
  // columns Ag = Y_k J_k of its whole subtree are known: row block j of the upper
  // triangle is J_j^T Ag over the subtree's columns (contiguous in depth-first order).
  for (int j = n - 1; j >= 0; --j) {
    const Joint& joint = model.joints[j];
    for (int k = 0; k < joint.nv; ++k) {
      const int col = joint.idx_v + k;
      data.Ag.col(col) = (data.oYcrb[j] * Motion<S>::fromVector(data.J.col(col))).toVector();
    }
    const int end = model.subtree_end[j] < n ? model.joints[model.subtree_end[j]].idx_v : model.nv;
    // 6-vector dot products, unrolled (a dynamic-size block product costs more in calls).
    for (int r = joint.idx_v; r < joint.idx_v + joint.nv; ++r)
      for (int c = r; c < end; ++c) data.M(r, c) = data.J.col(r).dot(data.Ag.col(c));
    if (joint.parent >= 0) data.oYcrb[joint.parent] += data.oYcrb[j];
  }
  // The lower triangle by symmetry, over the same structure.
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    const int end = model.subtree_end[j] < n ? model.joints[model.subtree_end[j]].idx_v : model.nv;
    for (int r = joint.idx_v; r < joint.idx_v + joint.nv; ++r)
      for (int c = r + 1; c < end; ++c) data.M(c, r) = data.M(r, c);
  }
  return data.M;
}

}  // namespace robodiff
