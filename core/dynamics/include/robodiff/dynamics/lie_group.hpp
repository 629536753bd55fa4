// Configuration-space operations on any scalar S (double, symbolic::Sym): q (+) dq and
// its inverse q1 (-) q0, free of branches on values, so that an expression such as
// integrateConfiguration(model, q, dt * v) traces into a graph whose automatic
// derivatives are exact, also at zero motion (dq = 0, q0 == q1).
//
// Revolute and prismatic joints add and subtract. The free-flyer [p; x y z w] moves by
// the SE(3) exponential of [linear; angular] in the base frame, as robodiff::integrate,
// but with the rotation kept as a quaternion product (no normalisation, no hemisphere
// flip), so the result is smooth in q and dq.
//
// Near zero angle the sin(t)/t-like coefficients switch to their Taylor series with
// selectPositive. Both branches are traced, and the graph's reverse mode multiplies the
// unselected one's partial derivatives by 0, so that branch must stay finite as well:
// it is evaluated at a harmless angle (and sqrt never at 0) instead of producing 0/0.
#pragma once

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>

#include "robodiff/model/model.hpp"
#include "robodiff/spatial/math.hpp"

namespace robodiff {
namespace lie_group_detail {

// Squared rotation angle below which the series are used: they are exact to double
// precision there (truncated at t^10 / 5e8), while the exact forms lose digits.
inline constexpr double kSmallAngle2 = 1e-3;

template <class S> S select(const S& condition, const S& if_positive, const S& otherwise) {
  return math::selectPositive<S>(condition, if_positive, otherwise);
}

template <class S> S atan2(const S& y, const S& x) {
  using std::atan2;
  return atan2(y, x);
}

// c[0] + c[1] x + c[2] x^2 + ... by Horner's rule.
template <class S, std::size_t N> S series(const S& x, const double (&c)[N]) {
  S r = S(c[N - 1]);
  for (std::size_t i = N - 1; i-- > 0;) r = r * x + S(c[i]);
  return r;
}

template <class S> struct Quaternion {
  Vec3<S> vec;
  S w;
};

template <class S> Quaternion<S> operator*(const Quaternion<S>& a, const Quaternion<S>& b) {
  return {a.w * b.vec + b.w * a.vec + a.vec.cross(b.vec), a.w * b.w - a.vec.dot(b.vec)};
}

// A free-flyer block of q: translation and unit quaternion (x y z w).
template <class S> struct Pose {
  Vec3<S> p;
  Quaternion<S> r;
};

template <class S> Pose<S> readPose(const VecX<S>& q, int iq) {
  return {Vec3<S>(q[iq], q[iq + 1], q[iq + 2]), {Vec3<S>(q[iq + 3], q[iq + 4], q[iq + 5]), q[iq + 6]}};
}

template <class S> void writePose(VecX<S>& q, int iq, const Pose<S>& m) {
  for (int k = 0; k < 3; ++k) {
    q[iq + k] = m.p[k];
    q[iq + 3 + k] = m.r.vec[k];
  }
  q[iq + 6] = m.r.w;
}

template <class S> Mat3<S> rotation(const Quaternion<S>& r) {
  return quaternionRotation<S>(r.vec[0], r.vec[1], r.vec[2], r.w);
}

// m * exp6([lin; ang]): the rotation r (x) (a ang, cos(t/2)) with a = sin(t/2)/t and
// the translation p + R V lin, V = I + b [ang]x + c [ang]x^2 (t = |ang|).
template <class S> Pose<S> expRight(const Pose<S>& m, const Vec3<S>& lin, const Vec3<S>& ang) {
  const S t2 = ang.squaredNorm();
  const S small = S(kSmallAngle2) - t2;  // > 0: the series
  const S t = math::sqrt(select(small, S(1), t2));  // the exact branch's angle, 1 when unused
  const S sh = math::sin(S(0.5) * t), ch = math::cos(S(0.5) * t);
  const S a = select(small, series(t2, {0.5, -1 / 48.0, 1 / 3840.0, -1 / 645120.0, 1 / 185794560.0}), sh / t);
  const S cw = select(small, series(t2, {1.0, -1 / 8.0, 1 / 384.0, -1 / 46080.0, 1 / 10321920.0}), ch);
  const S b = S(2) * a * a;  // (1 - cos t) / t^2 = 2 sin^2(t/2) / t^2, no cancellation
  const S c = select(small, series(t2, {1 / 6.0, -1 / 120.0, 1 / 5040.0, -1 / 362880.0, 1 / 39916800.0}),
                     (t - S(2) * sh * ch) / (t * t * t));  // (t - sin t) / t^3
  const Vec3<S> wl = ang.cross(lin);
  const Vec3<S> vl = lin + b * wl + c * ang.cross(wl);
  return {m.p + rotation(m.r) * vl, m.r * Quaternion<S>{a * ang, cw}};
}

// log6(m0^-1 m1) as [lin; ang]: the rotation from r = conj(r0) (x) r1 on its w >= 0
// side (the shorter way, angle <= pi), the translation V(ang)^-1 R0^T (p1 - p0).
template <class S> void logRelative(const Pose<S>& m0, const Pose<S>& m1, Vec3<S>& lin, Vec3<S>& ang) {
  const Quaternion<S> rel = Quaternion<S>{-m0.r.vec, m0.r.w} * m1.r;
  const S sign = select(rel.w, S(1), S(-1));  // piecewise constant: no derivative
  const Vec3<S> v = sign * rel.vec;
  const S w = sign * rel.w;
  const S s2 = v.squaredNorm();                         // sin^2(theta/2) for a unit r
  const S small = S(0.25 * kSmallAngle2) - s2;          // > 0: the series (theta ~ 2 s)
  const S s = math::sqrt(select(small, S(1), s2));      // the exact branch's |v|, 1 when unused
  const S ws = select(small, w, S(1));                  // the series' w, 1 when unused (w may be 0)
  // f = theta / |v| with theta = 2 atan2(|v|, w), so that ang = f v and theta^2 = f^2 s2;
  // as a series in x = s2 / w^2: (2 / w) atan(sqrt x) / sqrt x.
  const S x = s2 / (ws * ws);
  const S f_series = series(x, {2.0, -2 / 3.0, 2 / 5.0, -2 / 7.0, 2 / 9.0}) / ws;
  const S theta = S(2) * atan2(s, w), f_exact = theta / s;
  const S f = select(small, f_series, f_exact);
  // V^-1 = I - [ang]x / 2 + e [ang]x^2, e = (1 - (theta/2) cot(theta/2)) / theta^2 and
  // (theta/2) cot(theta/2) = w f / 2 (the ratio cos/sin = w / |v| needs no unit norm).
  const S theta2_series = f_series * f_series * s2;
  const S e = select(small, series(theta2_series, {1 / 12.0, 1 / 720.0, 1 / 30240.0, 1 / 1209600.0, 1 / 47900160.0}),
                     (S(1) - S(0.5) * w * f_exact) / (theta * theta));
  ang = f * v;
  const Vec3<S> pr = rotation(m0.r).transpose() * (m1.p - m0.p);
  const Vec3<S> wp = ang.cross(pr);
  lin = pr - S(0.5) * wp + e * ang.cross(wp);
}

inline void checkSize(const char* what, Eigen::Index actual, int expected) {
  if (actual != expected)
    throw std::invalid_argument(std::string(what) + " has size " + std::to_string(actual) + ", expected " +
                                std::to_string(expected));
}

}  // namespace lie_group_detail

// q (+) dq: q moved by the tangent vector dq (size nv), the free-flyer in its base frame.
template <class S>
VecX<S> integrateConfiguration(const Model& model, const VecX<S>& q, const VecX<S>& dq) {
  lie_group_detail::checkSize("integrateConfiguration: q", q.size(), model.nq);
  lie_group_detail::checkSize("integrateConfiguration: dq", dq.size(), model.nv);
  VecX<S> out = q;
  for (const Joint& j : model.joints) {
    if (j.type != JointType::FreeFlyer) {
      out[j.idx_q] = q[j.idx_q] + dq[j.idx_v];
      continue;
    }
    const int iv = j.idx_v;
    const Vec3<S> lin(dq[iv], dq[iv + 1], dq[iv + 2]), ang(dq[iv + 3], dq[iv + 4], dq[iv + 5]);
    const lie_group_detail::Pose<S> m = lie_group_detail::readPose(q, j.idx_q);
    lie_group_detail::writePose(out, j.idx_q, lie_group_detail::expRight(m, lin, ang));
  }
  return out;
}

// q1 (-) q0: the tangent vector d with integrateConfiguration(q0, d) == q1 (the
// free-flyer's rotation taken the shorter way, |angle| <= pi).
template <class S>
VecX<S> differenceConfiguration(const Model& model, const VecX<S>& q0, const VecX<S>& q1) {
  lie_group_detail::checkSize("differenceConfiguration: q0", q0.size(), model.nq);
  lie_group_detail::checkSize("differenceConfiguration: q1", q1.size(), model.nq);
  VecX<S> d(model.nv);
  for (const Joint& j : model.joints) {
    if (j.type != JointType::FreeFlyer) {
      d[j.idx_v] = q1[j.idx_q] - q0[j.idx_q];
      continue;
    }
    Vec3<S> lin, ang;
    const lie_group_detail::Pose<S> m0 = lie_group_detail::readPose(q0, j.idx_q);
    const lie_group_detail::Pose<S> m1 = lie_group_detail::readPose(q1, j.idx_q);
    lie_group_detail::logRelative(m0, m1, lin, ang);
    for (int k = 0; k < 3; ++k) {
      d[j.idx_v + k] = lin[k];
      d[j.idx_v + 3 + k] = ang[k];
    }
  }
  return d;
}

}  // namespace robodiff
