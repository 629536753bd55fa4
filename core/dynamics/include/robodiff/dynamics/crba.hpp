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
  InertiaSum<S> out;
  out.mass = I.mass;
  Vec3<S> c = oMi.act(I.lever);
  out.h = I.mass * c;
  Mat3<S> cx = skew<S>(c);
  out.rotational = oMi.rotation * I.inertia * oMi.rotation.transpose() - I.mass * (cx * cx);
  return out;
}

template <class S, class Q> const MatX<S>& crba(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  for (int j = 0; j < model.njoints(); ++j) {
    const Joint& joint = model.joints[j];
    data.liMi[j] = jointPlacement<S>(joint, q);
    data.oMi[j] = joint.parent >= 0 ? data.oMi[joint.parent] * data.liMi[j] : data.liMi[j];
    for (int k = 0; k < joint.nv; ++k)
      data.J.col(joint.idx_v + k) = data.oMi[j].act(subspaceColumn<S>(joint, k)).toVector();
    data.oYcrb[j] = worldInertia(model.bodies[j], data.oMi[j]);
  }
  for (int j = model.njoints() - 1; j >= 0; --j) {
    const Joint& joint = model.joints[j];
    for (int k = 0; k < joint.nv; ++k) {
      const int col = joint.idx_v + k;
      Force<S> F = data.oYcrb[j] * Motion<S>::fromVector(data.J.col(col));
      // Row i of column `col` for every joint i from j up to the root.
      for (int i = j; i >= 0; i = model.joints[i].parent) {
        const Joint& ancestor = model.joints[i];
        for (int r = 0; r < ancestor.nv; ++r) {
          const int row = ancestor.idx_v + r;
          if (row > col) continue;  // the lower triangle is filled by symmetry below
          const Motion<S> Jr = Motion<S>::fromVector(data.J.col(row));
          data.M(row, col) = Jr.dot(F);
          data.M(col, row) = data.M(row, col);
        }
      }
    }
    if (joint.parent >= 0) data.oYcrb[joint.parent] += data.oYcrb[j];
  }
  return data.M;
}

}  // namespace robodiff
