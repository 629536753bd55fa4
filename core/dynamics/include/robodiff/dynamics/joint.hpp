// What each joint type contributes to the algorithms: its placement as a function of q,
// its motion subspace S (constant in the joint frame for every supported type, so the
// joint's own bias acceleration is zero) and the projection S^T f. Branches here are on
// the joint's type (structure), never on values.
#pragma once

#include "robodiff/dynamics/data.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff {

// The model's double constants seen as scalars of type S (a reference when S is double).
template <class S> decltype(auto) asScalar(const SE3<double>& m) {
  if constexpr (std::is_same_v<S, double>) return (m);
  else return m.template cast<S>();
}
template <class S> decltype(auto) asScalar(const Inertia<double>& i) {
  if constexpr (std::is_same_v<S, double>) return (i);
  else return i.template cast<S>();
}
template <class S> decltype(auto) asScalar(const Eigen::Vector3d& x) {
  if constexpr (std::is_same_v<S, double>) return (x);
  else return Vec3<S>(x.template cast<S>());
}

namespace detail {
inline int axisIndex(AxisKind k) { return k == AxisKind::X ? 0 : k == AxisKind::Y ? 1 : 2; }
}  // namespace detail

// Placement of the joint frame in its parent joint's frame at configuration q (full q).
template <class S, class Q> SE3<S> jointPlacement(const Joint& joint, const Eigen::MatrixBase<Q>& q) {
  const auto& P = asScalar<S>(joint.placement);
  switch (joint.type) {
    case JointType::Revolute: {
      const S& angle = q[joint.idx_q];
      if (joint.axis_kind == AxisKind::Unaligned)
        return {P.rotation * axisAngleRotation<S>(joint.axis, angle), P.translation};
      const S s = math::sin(angle), c = math::cos(angle);
      // Rotating about coordinate axis k mixes the other two columns of P.rotation.
      const int k = detail::axisIndex(joint.axis_kind), i = (k + 1) % 3, l = (k + 2) % 3;
      SE3<S> out;
      out.translation = P.translation;
      out.rotation.col(k) = P.rotation.col(k);
      out.rotation.col(i) = c * P.rotation.col(i) + s * P.rotation.col(l);
      out.rotation.col(l) = c * P.rotation.col(l) - s * P.rotation.col(i);
      return out;
    }
    case JointType::Prismatic:
      return {P.rotation, P.translation + P.rotation * (asScalar<S>(joint.axis) * q[joint.idx_q])};
    case JointType::FreeFlyer: {
      const int i = joint.idx_q;
      SE3<S> m{quaternionRotation<S>(q[i + 3], q[i + 4], q[i + 5], q[i + 6]),
               Vec3<S>(q[i], q[i + 1], q[i + 2])};
      return P * m;
    }
  }
  return {};
}

// S * (the joint's segment of the velocity-like vector x).
template <class S, class X> Motion<S> jointMotion(const Joint& joint, const Eigen::MatrixBase<X>& x) {
  Motion<S> m;
  switch (joint.type) {
    case JointType::Revolute:
    case JointType::Prismatic: {
      Vec3<S>& part = joint.type == JointType::Revolute ? m.angular : m.linear;
      const S& qd = x[joint.idx_v];
      if (joint.axis_kind == AxisKind::Unaligned) part = asScalar<S>(joint.axis) * qd;
      else part[detail::axisIndex(joint.axis_kind)] = qd;
      return m;
    }
    case JointType::FreeFlyer: {
      const int i = joint.idx_v;
      m.linear = Vec3<S>(x[i], x[i + 1], x[i + 2]);
      m.angular = Vec3<S>(x[i + 3], x[i + 4], x[i + 5]);
      return m;
    }
  }
  return m;
}

// Column k of the joint's motion subspace, in the joint frame.
template <class S> Motion<S> subspaceColumn(const Joint& joint, int k) {
  Motion<S> m;
  switch (joint.type) {
    case JointType::Revolute: m.angular = asScalar<S>(joint.axis); break;
    case JointType::Prismatic: m.linear = asScalar<S>(joint.axis); break;
    case JointType::FreeFlyer: (k < 3 ? m.linear : m.angular)[k % 3] = S(1); break;
  }
  return m;
}

// R S_k: column k of the joint's motion subspace rotated by R (world-aligned axes, no
// change of origin). Aligned axes take R's column: no products, in double too.
template <class S> Motion<S> rotatedSubspaceColumn(const Joint& joint, const Mat3<S>& R, int k) {
  Motion<S> m;
  if (joint.type == JointType::FreeFlyer) {
    (k < 3 ? m.linear : m.angular) = R.col(k % 3);
  } else {
    Vec3<S>& part = joint.type == JointType::Revolute ? m.angular : m.linear;
    if (joint.axis_kind == AxisKind::Unaligned) part = R * asScalar<S>(joint.axis);
    else part = R.col(detail::axisIndex(joint.axis_kind));
  }
  return m;
}

// Column k of a joint's motion subspace in the world frame, given the joint's oMi.
template <class S> Vec6<S> worldSubspaceColumn(const Joint& joint, const SE3<S>& oMi, int k) {
  if (joint.type == JointType::Revolute && joint.axis_kind != AxisKind::Unaligned) {
    Vec6<S> col;
    const auto axis = oMi.rotation.col(detail::axisIndex(joint.axis_kind));
    col.template tail<3>() = axis;
    col.template head<3>() = oMi.translation.cross(Vec3<S>(axis));
    return col;
  }
  return oMi.act(subspaceColumn<S>(joint, k)).toVector();
}

// S^T f: the generalised force of spatial force f on the joint, component k.
template <class S> S projectForce(const Joint& joint, const Force<S>& f, int k) {
  switch (joint.type) {
    case JointType::Revolute:
    case JointType::Prismatic: {
      const Vec3<S>& part = joint.type == JointType::Revolute ? f.angular : f.linear;
      if (joint.axis_kind == AxisKind::Unaligned) return asScalar<S>(joint.axis).dot(part);
      return part[detail::axisIndex(joint.axis_kind)];
    }
    case JointType::FreeFlyer:
      return k < 3 ? f.linear[k] : f.angular[k - 3];
  }
  return S(0);
}

// S^T Y S-style products need S applied to a 6x6 from the right: returns Y * S.
template <class S> JointBlock<S> rightMultiplySubspace(const Joint& joint, const Mat6<S>& y) {
  JointBlock<S> out(6, joint.nv);
  for (int k = 0; k < joint.nv; ++k) {
    if (joint.type == JointType::FreeFlyer) {
      out.col(k) = y.col(k);
    } else if (joint.axis_kind != AxisKind::Unaligned) {
      int offset = joint.type == JointType::Revolute ? 3 : 0;
      out.col(k) = y.col(offset + detail::axisIndex(joint.axis_kind));
    } else {
      out.col(k) = y * subspaceColumn<S>(joint, k).toVector();
    }
  }
  return out;
}

// S^T x for a 6-vector x ([linear; angular]).
template <class S, class X> JointVector<S> projectVector(const Joint& joint, const Eigen::MatrixBase<X>& x) {
  Force<S> f{x.template head<3>(), x.template tail<3>()};
  JointVector<S> out(joint.nv);
  for (int k = 0; k < joint.nv; ++k) out[k] = projectForce<S>(joint, f, k);
  return out;
}

}  // namespace robodiff
