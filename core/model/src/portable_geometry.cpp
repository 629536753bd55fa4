// Portable model arithmetic (portable_geometry.hpp). Element by element, in a fixed order
// of IEEE operations: sums run left to right; compiled with -ffp-contract=off.
#include "portable_geometry.hpp"

#include <cmath>

#include "portable_trig.hpp"

namespace robodiff::portable {
namespace {

// Row i of a times column j of b.
double rowTimesColumn(const Mat3<double>& a, int i, const Mat3<double>& b, int j) {
  return (a(i, 0) * b(0, j) + a(i, 1) * b(1, j)) + a(i, 2) * b(2, j);
}

// a * v + p.
Vec3<double> affine(const Mat3<double>& a, const Vec3<double>& v, const Vec3<double>& p) {
  Vec3<double> out;
  for (int i = 0; i < 3; ++i) out(i) = ((a(i, 0) * v(0) + a(i, 1) * v(1)) + a(i, 2) * v(2)) + p(i);
  return out;
}

// skew(d) * skew(d) = d d^T - |d|^2 Id, with the diagonal as -(sum of the two other
// squares) (no cancellation).
double skewSquared(const Vec3<double>& d, int i, int j) {
  if (i != j) return d(i) * d(j);
  const int a = (i + 1) % 3, b = (i + 2) % 3;
  return -(d(a) * d(a) + d(b) * d(b));
}

}  // namespace

Mat3<double> rpyRotation(double roll, double pitch, double yaw) {
  const SinCos r = sinCos(roll), p = sinCos(pitch), y = sinCos(yaw);
  Mat3<double> m;
  m(0, 0) = y.cos * p.cos;
  m(0, 1) = (y.cos * p.sin) * r.sin - y.sin * r.cos;
  m(0, 2) = (y.cos * p.sin) * r.cos + y.sin * r.sin;
  m(1, 0) = y.sin * p.cos;
  m(1, 1) = (y.sin * p.sin) * r.sin + y.cos * r.cos;
  m(1, 2) = (y.sin * p.sin) * r.cos - y.cos * r.sin;
  m(2, 0) = -p.sin;
  m(2, 1) = p.cos * r.sin;
  m(2, 2) = p.cos * r.cos;
  return m;
}

SE3<double> compose(const SE3<double>& a, const SE3<double>& b) {
  SE3<double> out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.rotation(i, j) = rowTimesColumn(a.rotation, i, b.rotation, j);
  out.translation = affine(a.rotation, b.translation, a.translation);
  return out;
}

Mat3<double> rotateInertia(const Mat3<double>& r, const Mat3<double>& i) {
  Mat3<double> ri;  // r * i
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) ri(a, b) = rowTimesColumn(r, a, i, b);
  Mat3<double> out;
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {  // (r i r^T)(a, b) = row a of ri . row b of r
      out(a, b) = (ri(a, 0) * r(b, 0) + ri(a, 1) * r(b, 1)) + ri(a, 2) * r(b, 2);
      out(b, a) = out(a, b);
    }
  return out;
}

Inertia<double> transformInertia(const Inertia<double>& body, const SE3<double>& aMb) {
  return {body.mass, affine(aMb.rotation, body.lever, aMb.translation), rotateInertia(aMb.rotation, body.inertia)};
}

Inertia<double> mergeInertias(const Inertia<double>& a, const Inertia<double>& b) {
  Inertia<double> out;
  const double mass = a.mass + b.mass;
  if (!(mass > 0)) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out.inertia(i, j) = a.inertia(i, j) + b.inertia(i, j);
    return out;
  }
  out.mass = mass;
  for (int i = 0; i < 3; ++i) out.lever(i) = (a.mass * a.lever(i) + b.mass * b.lever(i)) / mass;
  Vec3<double> da, db;  // the bodies' centres of mass from the union's
  for (int i = 0; i < 3; ++i) da(i) = a.lever(i) - out.lever(i), db(i) = b.lever(i) - out.lever(i);
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {  // the upper triangle, mirrored: exactly symmetric
      out.inertia(i, j) =
          ((a.inertia(i, j) - a.mass * skewSquared(da, i, j)) + b.inertia(i, j)) - b.mass * skewSquared(db, i, j);
      out.inertia(j, i) = out.inertia(i, j);
    }
  return out;
}

Vec3<double> normalized(const Vec3<double>& v) {
  const double n2 = (v(0) * v(0) + v(1) * v(1)) + v(2) * v(2);
  if (!(n2 > 0)) return v;
  const double n = std::sqrt(n2);
  return {v(0) / n, v(1) / n, v(2) / n};
}

}  // namespace robodiff::portable
