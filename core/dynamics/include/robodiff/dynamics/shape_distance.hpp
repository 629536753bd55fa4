// Geometry of the `distance` primitive: the signed distance between two simple shapes
// (spheres and capsules) attached to robot frames, templated on the scalar.
//
// Every shape is a core segment swept by a radius (a sphere's segment is a point), so
// the distance is |c_a - c_b| - r_a - r_b with c_a, c_b the closest points of the two
// core segments. The computation is branch-free on values (min, max, selectPositive),
// so it traces into a straight-line graph valid for every placement; what depends only
// on the shapes (which of them are points) is decided at trace time.
//
// Derivative rule (envelope theorem): with the nearest points held fixed on their
// bodies, d distance = normal . (d c_a - d c_b); the motion of the nearest points along
// their segments does not contribute (normal is orthogonal to the segment where the
// parameter is interior, and the clamped parameter is locally constant).
//
// When the core segments touch (c_a == c_b) the normal is undefined (0/0) and so is the
// derivative of the norm: the caller must keep the cores apart (radii > 0 give margin).
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "robodiff/spatial/math.hpp"
#include "robodiff/spatial/se3.hpp"

namespace robodiff {

// A shape in the coordinates of its frame: a sphere is centred at `a` (b unused); a
// capsule is the segment a-b swept by `radius`.
struct Shape {
  enum class Kind { Sphere, Capsule } kind = Kind::Sphere;
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius = 0.0;

  static Shape sphere(const Eigen::Vector3d& center, double radius) {
    return {Kind::Sphere, center, center, radius};
  }
  static Shape capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
    return {Kind::Capsule, a, b, radius};
  }
  // The core is a point: a sphere, or a capsule of zero length (known at trace time).
  bool isPoint() const { return kind == Kind::Sphere || a == b; }
};

template <class S> struct ShapeDistance {
  S distance;         // between the surfaces, negative when they overlap
  Vec3<S> point_a;    // nearest point of A's core (world), c_a
  Vec3<S> point_b;    // nearest point of B's core (world), c_b
  Vec3<S> normal;     // (c_a - c_b) / |c_a - c_b|: from B towards A
};

namespace shape_detail {

// Branch-free choices for double; a symbolic scalar brings its own by ADL. fmin/fmax
// are what the graph evaluates, so traced and double results agree bit for bit.
inline double min(double x, double y) { return std::fmin(x, y); }
inline double max(double x, double y) { return std::fmax(x, y); }
inline double selectPositive(double condition, double if_positive, double otherwise) {
  return condition > 0 ? if_positive : otherwise;
}

template <class S> S clamp01(const S& x) { return min(max(x, S(0)), S(1)); }

// Segments whose sin^2(angle) is below this are treated as parallel (the distance is
// then off by at most ~ length * angle < length * 1e-7).
inline constexpr double kParallel = 1e-14;

// The parameter in [0, 1] of the point of the segment start + u * dir nearest to p;
// dir_sq = |dir|^2 > 0 (the segment has non-zero length, known at trace time).
template <class S>
S nearestOnSegment(const Vec3<S>& p, const Vec3<S>& start, const Vec3<S>& dir, const S& dir_sq) {
  return clamp01(S(dir.dot(p - start) / dir_sq));
}

// The parameters (s, t) of the closest points p1 + s d1, p2 + t d2 of two segments of
// non-zero length (the clamped closest-point computation of Ericson, Real-Time
// Collision Detection 5.1.9, without branches).
template <class S>
void closestSegmentSegment(const Vec3<S>& p1, const Vec3<S>& d1, const Vec3<S>& p2, const Vec3<S>& d2,
                           S& s, S& t) {
  const Vec3<S> r = p1 - p2;
  const S a = d1.dot(d1), e = d2.dot(d2), b = d1.dot(d2);
  const S c = d1.dot(r), f = d2.dot(r);
  const S denom = a * e - b * b;  // |d1 x d2|^2 >= 0
  // Positive when the lines are not parallel. The division uses a safe denominator so
  // that the branch not selected never makes inf/NaN (in values or derivatives).
  const S not_parallel = denom - kParallel * (a * e);
  const S safe_denom = selectPositive(not_parallel, denom, S(1));
  // s on the infinite lines, clamped; s = 0 (any point) for parallel lines.
  s = selectPositive(not_parallel, clamp01(S((b * f - c * e) / safe_denom)), S(0));
  // t nearest to P(s), clamped; then s nearest to Q(t), clamped. When t is not clamped
  // this gives back s; when it is, this is the correction of the clamped case; for
  // parallel segments the two projections land on a closest pair.
  t = clamp01(S((b * s + f) / e));
  s = clamp01(S((b * t - c) / a));
}

}  // namespace shape_detail

// The signed distance between shape A on frame a and shape B on frame b, placed in the
// world by oMa and oMb, with the nearest points of the cores and the normal.
template <class S>
ShapeDistance<S> shapeDistance(const Shape& A, const SE3<S>& oMa, const Shape& B, const SE3<S>& oMb) {
  using shape_detail::closestSegmentSegment;
  using shape_detail::nearestOnSegment;
  // Core segments in the world: start p, direction d (d unused for a point).
  const Vec3<S> pa = oMa.act(A.a.template cast<S>());
  const Vec3<S> pb = oMb.act(B.a.template cast<S>());
  const Vec3<S> da = oMa.rotation * (A.b - A.a).template cast<S>();
  const Vec3<S> db = oMb.rotation * (B.b - B.a).template cast<S>();

  ShapeDistance<S> out;
  // The cases are chosen from the shapes (constants), never from values.
  if (A.isPoint() && B.isPoint()) {
    out.point_a = pa;
    out.point_b = pb;
  } else if (A.isPoint()) {
    out.point_a = pa;
    out.point_b = pb + db * nearestOnSegment<S>(pa, pb, db, db.dot(db));
  } else if (B.isPoint()) {
    out.point_a = pa + da * nearestOnSegment<S>(pb, pa, da, da.dot(da));
    out.point_b = pb;
  } else {
    S s, t;
    closestSegmentSegment<S>(pa, da, pb, db, s, t);
    out.point_a = pa + da * s;
    out.point_b = pb + db * t;
  }
  const Vec3<S> core = out.point_a - out.point_b;
  const S core_distance = math::sqrt(S(core.dot(core)));  // undefined derivative at 0
  out.distance = core_distance - S(A.radius + B.radius);
  out.normal = core / core_distance;
  return out;
}

// The signed distance alone.
template <class S>
S shapeDistanceValue(const Shape& A, const SE3<S>& oMa, const Shape& B, const SE3<S>& oMb) {
  return shapeDistance(A, oMa, B, oMb).distance;
}

}  // namespace robodiff
