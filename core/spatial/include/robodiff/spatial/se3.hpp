// Rigid transform aMb: maps coordinates in frame b to frame a (x_a = R x_b + p),
// with the spatial actions that move motions and forces between the two frames.
#pragma once

#include "robodiff/spatial/force.hpp"
#include "robodiff/spatial/math.hpp"
#include "robodiff/spatial/motion.hpp"

namespace robodiff {

template <class S> struct SE3 {
  Mat3<S> rotation = Mat3<S>::Identity();
  Vec3<S> translation = Vec3<S>::Zero();

  static SE3 Identity() { return SE3{}; }

  template <class T> SE3<T> cast() const {
    return {rotation.template cast<T>(), translation.template cast<T>()};
  }

  // Composition: (aMb * bMc) = aMc.
  SE3 operator*(const SE3& m) const {
    return {rotation * m.rotation, rotation * m.translation + translation};
  }
  SE3 inverse() const {
    Mat3<S> rt = rotation.transpose();
    return {rt, -(rt * translation)};
  }
  Vec3<S> act(const Vec3<S>& point) const { return rotation * point + translation; }
  Vec3<S> actInv(const Vec3<S>& point) const { return rotation.transpose() * (point - translation); }

  // A motion expressed in b, re-expressed in a.
  Motion<S> act(const Motion<S>& m) const {
    Vec3<S> w = rotation * m.angular;
    return {rotation * m.linear + translation.cross(w), w};
  }
  // A motion expressed in a, re-expressed in b.
  Motion<S> actInv(const Motion<S>& m) const {
    Mat3<S> rt = rotation.transpose();
    return {rt * (m.linear - translation.cross(m.angular)), rt * m.angular};
  }
  // A force expressed in b, re-expressed in a.
  Force<S> act(const Force<S>& f) const {
    Vec3<S> lin = rotation * f.linear;
    return {lin, rotation * f.angular + translation.cross(lin)};
  }
  // A force expressed in a, re-expressed in b.
  Force<S> actInv(const Force<S>& f) const {
    Mat3<S> rt = rotation.transpose();
    return {rt * f.linear, rt * (f.angular - translation.cross(f.linear))};
  }

  // Column-wise actions on 6xN blocks of motions / forces ([linear; angular] rows).
  template <class Derived> Matrix6X<S> actMotions(const Eigen::MatrixBase<Derived>& m) const {
    return mapColumns<Motion<S>>(m, [this](const Motion<S>& x) { return act(x); });
  }
  template <class Derived> Matrix6X<S> actInvMotions(const Eigen::MatrixBase<Derived>& m) const {
    return mapColumns<Motion<S>>(m, [this](const Motion<S>& x) { return actInv(x); });
  }
  template <class Derived> Matrix6X<S> actForces(const Eigen::MatrixBase<Derived>& f) const {
    return mapColumns<Force<S>>(f, [this](const Force<S>& x) { return act(x); });
  }

  // The 6x6 matrix of a symmetric spatial operator (inertia, articulated inertia)
  // expressed in b, re-expressed in a: X^T Y X with X the motion transform a -> b.
  // The symmetric blocks are computed on and above the diagonal and mirrored, so that a
  // traced result is symmetric node for node (and costs 6 entries, not 9, per block).
  Mat6<S> actOnSymmetric(const Mat6<S>& y) const {
    const Mat3<S>& r = rotation;
    const Mat3<S> a = upperTimesMirrored(r * y.template block<3, 3>(0, 0), r);
    const Mat3<S> b = r * y.template block<3, 3>(0, 3) * r.transpose();
    const Mat3<S> c = upperTimesMirrored(r * y.template block<3, 3>(3, 3), r);
    const Mat3<S> px = skew<S>(translation);
    // Shift of the moment reference point from b's origin to a's origin.
    const Mat3<S> b2 = b - a * px;
    const Mat3<S> pb = px * b;
    const Mat3<S> pa = px * a;  // c2 = c + pb + pb^T - px a px
    Mat3<S> c2;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) c2(i, j) = c2(j, i) = c(i, j) + pb(i, j) + pb(j, i) - pa.row(i).dot(px.col(j));
    Mat6<S> out;
    out.template block<3, 3>(0, 0) = a;
    out.template block<3, 3>(0, 3) = b2;
    out.template block<3, 3>(3, 0) = b2.transpose();
    out.template block<3, 3>(3, 3) = c2;
    return out;
  }

 private:
  // t m^T for a product known to be symmetric: the entries on and above the diagonal,
  // mirrored below.
  static Mat3<S> upperTimesMirrored(const Mat3<S>& t, const Mat3<S>& m) {
    Mat3<S> out;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) out(i, j) = out(j, i) = t.row(i).dot(m.row(j));
    return out;
  }

  // Applies `action` to every column of m read as a spatial vector of type V.
  template <class V, class Derived, class Action>
  static Matrix6X<S> mapColumns(const Eigen::MatrixBase<Derived>& m, Action action) {
    Matrix6X<S> out(6, m.cols());
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      V r = action(V{m.template block<3, 1>(0, c), m.template block<3, 1>(3, c)});
      out.template block<3, 1>(0, c) = r.linear;
      out.template block<3, 1>(3, c) = r.angular;
    }
    return out;
  }
};

// Rotation of angle `angle` about a unit axis (Rodrigues), branch-free.
template <class S> inline Mat3<S> axisAngleRotation(const Vec3<double>& axis, const S& angle) {
  const S s = math::sin(angle), c = math::cos(angle);
  const S t = S(1) - c;
  const double x = axis.x(), y = axis.y(), z = axis.z();
  Mat3<S> r;
  r << t * (x * x) + c, t * (x * y) - s * z, t * (x * z) + s * y,
       t * (x * y) + s * z, t * (y * y) + c, t * (y * z) - s * x,
       t * (x * z) - s * y, t * (y * z) + s * x, t * (z * z) + c;
  return r;
}

// Rotation matrix of a unit quaternion (x, y, z, w), branch-free, no normalisation.
template <class S>
inline Mat3<S> quaternionRotation(const S& x, const S& y, const S& z, const S& w) {
  const S tx = S(2) * x, ty = S(2) * y, tz = S(2) * z;
  const S twx = tx * w, twy = ty * w, twz = tz * w;
  const S txx = tx * x, txy = ty * x, txz = tz * x;
  const S tyy = ty * y, tyz = tz * y, tzz = tz * z;
  Mat3<S> r;
  r << S(1) - (tyy + tzz), txy - twz, txz + twy,
       txy + twz, S(1) - (txx + tzz), tyz - twx,
       txz - twy, tyz + twx, S(1) - (txx + tyy);
  return r;
}

}  // namespace robodiff
