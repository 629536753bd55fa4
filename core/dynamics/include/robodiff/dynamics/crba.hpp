// Composite Rigid Body Algorithm: the joint-space mass matrix M(q), full and symmetric,
// in two forms; crba() picks by scalar.
//
// crbaJointFrames (Featherstone's form, Pinocchio's local convention): in a joint's own
// frame a body's inertia is a constant, a composite inertia moves to its parent's frame by
// the joint's placement alone, and joint j's column block F = Y_j S_j climbs its ancestors
// one placement at a time, M(i, j) = S_i^T F at each ancestor i. Traced, the first
// transforms act on constants and the rotations about a joint axis are sparse: 64% fewer
// operations than the world-frame form for a Panda, 60% for Talos.
// crbaWorldFrame (Pinocchio's world convention): fewer floating-point operations when
// nothing folds, so it is the double-precision form (the joint-frame form takes 1.2-1.4x its
// time there), and traced beside RNEA's analytic partials it shares their oMi.
// Entries of joints on different branches stay zero.
#pragma once

#include <cmath>
#include <type_traits>

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/joint.hpp"

namespace robodiff {

namespace detail {

// Column `col` of M on and above the diagonal: the force f (in joint j's frame) projected on
// joint j's rows, then moved up to each ancestor and projected on its rows.
template <class S> void crbaColumn(const Model& model, Data<S>& data, int j, int col, Force<S> f) {
  for (int i = j;; i = model.joints[i].parent) {
    const Joint& joint = model.joints[i];
    for (int r = 0; r < joint.nv; ++r) data.M(joint.idx_v + r, col) = projectForce<S>(joint, f, r);
    if (joint.parent < 0) return;
    f = data.liMi[i].act(f);
  }
}

// M's lower triangle from its upper one: a joint's rows against its subtree's columns
// (contiguous in depth-first order); entries of joints on different branches stay zero.
template <class S> void mirrorUpperTriangle(const Model& model, MatX<S>& M) {
  const int n = model.njoints();
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    const int end = model.subtree_end[j] < n ? model.joints[model.subtree_end[j]].idx_v : model.nv;
    for (int r = joint.idx_v; r < joint.idx_v + joint.nv; ++r)
      for (int c = r + 1; c < end; ++c) M(c, r) = M(r, c);
  }
}

// Whether every entry of a rotation is 0 or +-1 (axes swapped or flipped, if at all).
inline bool permutesAxes(const Mat3<double>& R) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (R(r, c) != 0.0 && std::abs(R(r, c)) != 1.0) return false;
  return true;
}

// Joint j's composite inertia in its parent's frame. A revolute joint about a coordinate
// axis whose placement only permutes axes: turned about the axis first
// (InertiaSum::rotatedAboutAxis), then moved by the placement, whose rotation costs nothing
// traced; any other joint: by liMi at once.
template <class S, class Q>
InertiaSum<S> compositeInParent(const Model& model, const Data<S>& data, int j, const Eigen::MatrixBase<Q>& q) {
  const Joint& joint = model.joints[j];
  if (joint.type != JointType::Revolute || joint.axis_kind == AxisKind::Unaligned || !permutesAxes(joint.placement.rotation))
    return data.Ycrb[j].transformedBy(data.liMi[j]);
  const S& angle = q[joint.idx_q];
  const InertiaSum<S> turned =
      data.Ycrb[j].rotatedAboutAxis(axisIndex(joint.axis_kind), S(math::cos(angle)), S(math::sin(angle)));
  return turned.transformedBy(asScalar<S>(joint.placement));
}

}  // namespace detail

template <class S, class Q>
const MatX<S>& crbaJointFrames(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  const int n = model.njoints();
  for (int j = 0; j < n; ++j) {
    data.liMi[j] = jointPlacement<S>(model.joints[j], q);
    data.Ycrb[j] = InertiaSum<S>::of(model.bodies[j]);
  }
  // Leaves to root: when joint j is reached its composite inertia is complete.
  for (int j = n - 1; j >= 0; --j) {
    const Joint& joint = model.joints[j];
    for (int k = 0; k < joint.nv; ++k)
      detail::crbaColumn(model, data, j, joint.idx_v + k, data.Ycrb[j] * subspaceColumn<S>(joint, k));
    if (joint.parent >= 0) data.Ycrb[joint.parent] += detail::compositeInParent(model, data, j, q);
  }
  detail::mirrorUpperTriangle(model, data.M);
  return data.M;
}

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

// The same M computed in the world frame: composite inertias are plain sums of the
// bodies' world inertias, and M(i, j) = J_i^T (Y_j J_j) for every joint i supporting joint
// j (its oMi and world subspace columns are what RNEA's analytic partials compute too).
template <class S, class Q> const MatX<S>& crbaWorldFrame(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  const int n = model.njoints();
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    data.liMi[j] = jointPlacement<S>(joint, q);
    data.oMi[j] = joint.parent >= 0 ? data.oMi[joint.parent] * data.liMi[j] : data.liMi[j];
    for (int k = 0; k < joint.nv; ++k) data.J.col(joint.idx_v + k) = worldSubspaceColumn(joint, data.oMi[j], k);
    data.Ycrb[j] = worldInertia(model.bodies[j], data.oMi[j]);
  }
  // Leaves to root. When joint j is reached its composite inertia is complete, and the
  // columns Ag = Y_k J_k of its whole subtree are known: row block j of the upper
  // triangle is J_j^T Ag over the subtree's columns (contiguous in depth-first order).
  for (int j = n - 1; j >= 0; --j) {
    const Joint& joint = model.joints[j];
    for (int k = 0; k < joint.nv; ++k) {
      const int col = joint.idx_v + k;
      data.Ag.col(col) = (data.Ycrb[j] * Motion<S>::fromVector(data.J.col(col))).toVector();
    }
    const int end = model.subtree_end[j] < n ? model.joints[model.subtree_end[j]].idx_v : model.nv;
    // 6-vector dot products, unrolled (a dynamic-size block product costs more in calls).
    for (int r = joint.idx_v; r < joint.idx_v + joint.nv; ++r)
      for (int c = r; c < end; ++c) data.M(r, c) = data.J.col(r).dot(data.Ag.col(c));
    if (joint.parent >= 0) data.Ycrb[joint.parent] += data.Ycrb[j];
  }
  detail::mirrorUpperTriangle(model, data.M);
  return data.M;
}

// M(q): in the world frame in double, in the joints' frames when traced.
template <class S, class Q> const MatX<S>& crba(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  if constexpr (std::is_same_v<S, double>) return crbaWorldFrame(model, data, q);
  else return crbaJointFrames(model, data, q);
}

// Which of the two forms computes M, where the caller knows better than the scalar.
enum class CrbaFrame { Joint, World };

template <class S, class Q>
const MatX<S>& crba(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q, CrbaFrame frame) {
  return frame == CrbaFrame::World ? crbaWorldFrame(model, data, q) : crbaJointFrames(model, data, q);
}

}  // namespace robodiff
