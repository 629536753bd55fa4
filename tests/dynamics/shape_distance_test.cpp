// shapeDistance on doubles against brute force: sphere-sphere, sphere-capsule and
// capsule-capsule (crossing, parallel, collinear, endpoint-nearest, overlapping), under
// non-trivial placements, plus random pairs (near-parallel ones included).
#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "robodiff/dynamics/shape_distance.hpp"

namespace robodiff {
namespace {

using Eigen::Vector3d;

struct Segment {
  Vector3d p, d;  // p + u d, u in [0, 1]
  Vector3d at(double u) const { return p + u * d; }
};

Segment worldCore(const Shape& shape, const SE3<double>& m) {
  Vector3d d = shape.kind == Shape::Kind::Sphere ? Vector3d::Zero() : Vector3d(m.rotation * (shape.b - shape.a));
  return {m.act(shape.a), d};
}

// Parameter of the point of `seg` nearest to x (exact: a clamped projection).
double project(const Segment& seg, const Vector3d& x) {
  double dd = seg.d.squaredNorm();
  return dd == 0 ? 0.0 : std::clamp(seg.d.dot(x - seg.p) / dd, 0.0, 1.0);
}

// min over u of |A(u) - B(nearest to A(u))|: convex in u. Dense samples of u, then a
// ternary search in the bracket around the best sample.
double sampledMinAlong(const Segment& a, const Segment& b) {
  auto g = [&](double u) { Vector3d x = a.at(u); return (x - b.at(project(b, x))).norm(); };
  const int n = 2000;
  int best = 0;
  double best_value = g(0);
  for (int i = 1; i <= n; ++i)
    if (double v = g(double(i) / n); v < best_value) best_value = v, best = i;
  double lo = std::max(0, best - 1) / double(n), hi = std::min(n, best + 1) / double(n);
  for (int k = 0; k < 200; ++k) {
    double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
    if (g(m1) < g(m2))
      hi = m2;
    else
      lo = m1;
  }
  return std::min(best_value, g(0.5 * (lo + hi)));
}

// Brute-force core distance: sampled along both segments (each with exact nearest
// points on the other), plus a plain grid of both segments as an upper bound.
struct BruteForce {
  double refined, grid;
};
BruteForce bruteForce(const Segment& a, const Segment& b) {
  BruteForce out{std::min(sampledMinAlong(a, b), sampledMinAlong(b, a)), INFINITY};
  const int n = 300;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) out.grid = std::min(out.grid, (a.at(double(i) / n) - b.at(double(j) / n)).norm());
  return out;
}

// Distance from x to a segment.
double offSegment(const Segment& seg, const Vector3d& x) { return (x - seg.at(project(seg, x))).norm(); }

SE3<double> placement(const Vector3d& axis, double angle, const Vector3d& translation) {
  return {axisAngleRotation<double>(axis.normalized(), angle), translation};
}

// Checks the result of A, B against brute force and its own consistency.
void expectMatchesBruteForce(const Shape& A, const SE3<double>& oMa, const Shape& B, const SE3<double>& oMb,
                             const std::string& label) {
  SCOPED_TRACE(label);
  ShapeDistance<double> r = shapeDistance(A, oMa, B, oMb);
  Segment ca = worldCore(A, oMa), cb = worldCore(B, oMb);
  BruteForce bf = bruteForce(ca, cb);
  double radii = A.radius + B.radius, core = r.distance + radii;
  // Never below the sampled minimum by more than rounding, and within 1e-6 of it.
  EXPECT_GE(core, bf.refined - 1e-12);
  EXPECT_LE(core, bf.refined + 1e-6);
  EXPECT_LE(core, bf.grid + 1e-6);  // no worse than any pair of samples
  // The points lie on their cores, and distance / normal are consistent with them.
  EXPECT_LT(offSegment(ca, r.point_a), 1e-12);
  EXPECT_LT(offSegment(cb, r.point_b), 1e-12);
  EXPECT_NEAR((r.point_a - r.point_b).norm() - radii, r.distance, 1e-12);
  if (core > 1e-9) {  // the normal is undefined where the cores touch
    EXPECT_NEAR(r.normal.norm(), 1.0, 1e-12);
    EXPECT_LT((r.normal * core - (r.point_a - r.point_b)).norm(), 1e-12);
  }
  EXPECT_EQ(shapeDistanceValue(A, oMa, B, oMb), r.distance);
}

const SE3<double> kOMa = placement({1, 2, 3}, 0.7, {0.3, -0.2, 0.5});
const SE3<double> kOMb = placement({-2, 1, 0.5}, -1.1, {-0.4, 0.6, 0.1});

// A shape given in world coordinates, re-expressed in the frame placed by oMf.
Shape inFrame(Shape s, const SE3<double>& oMf) {
  s.a = oMf.actInv(s.a);
  s.b = oMf.actInv(s.b);
  return s;
}

void expectWorld(const Shape& A, const Shape& B, const std::string& label, double expected_distance) {
  Shape a = inFrame(A, kOMa), b = inFrame(B, kOMb);
  expectMatchesBruteForce(a, kOMa, b, kOMb, label);
  expectMatchesBruteForce(b, kOMb, a, kOMa, label + " (swapped)");
  EXPECT_NEAR(shapeDistanceValue(a, kOMa, b, kOMb), expected_distance, 1e-12) << label;
}

TEST(ShapeDistance, SphereSphere) {
  expectWorld(Shape::sphere({0, 0, 0}, 0.5), Shape::sphere({3, 4, 0}, 1.0), "separated", 3.5);
  expectWorld(Shape::sphere({0, 0, 0}, 0.5), Shape::sphere({0, 0.6, 0.8}, 1.0), "overlapping", -0.5);
  ShapeDistance<double> r = shapeDistance(Shape::sphere({1, 0, 0}, 0.1), SE3<double>::Identity(),
                                          Shape::sphere({0, 0, 0}, 0.2), SE3<double>::Identity());
  EXPECT_TRUE(r.normal.isApprox(Vector3d(1, 0, 0)));  // from B towards A
}

TEST(ShapeDistance, SphereCapsule) {
  Shape cap = Shape::capsule({-1, 0, 0}, {1, 0, 0}, 0.2);
  expectWorld(Shape::sphere({0.3, 2, 0}, 0.5), cap, "interior", 1.3);
  expectWorld(Shape::sphere({3, 0, 4}, 0.5), cap, "beyond endpoint", std::hypot(2.0, 4.0) - 0.7);
  expectWorld(Shape::sphere({-1.5, 0, 0}, 0.5), cap, "collinear beyond endpoint", -0.2);
  expectWorld(Shape::sphere({0.2, 0.1, 0.1}, 0.1), cap, "overlapping", std::hypot(0.1, 0.1) - 0.3);
  expectWorld(Shape::capsule({0.3, 2, 0}, {0.3, 2, 0}, 0.5), cap, "zero-length capsule", 1.3);
}

TEST(ShapeDistance, CapsuleCapsule) {
  Shape x = Shape::capsule({-1, 0, 0}, {1, 0, 0}, 0.1);
  auto cap = [](Vector3d a, Vector3d b) { return Shape::capsule(a, b, 0.2); };
  expectWorld(x, cap({0.3, -1, 1}, {0.3, 1, 1}), "crossing", 0.7);
  expectWorld(x, cap({0.3, -1, 0.05}, {0.3, 1, 0.05}), "crossing, overlapping", -0.25);
  expectWorld(x, cap({0.3, -1, 0}, {0.3, 1, 0}), "crossing, intersecting cores", -0.3);
  expectWorld(x, cap({-0.5, 0, 1}, {2, 0, 1}), "parallel, overlapping span", 0.7);
  expectWorld(x, cap({2, 0, 1}, {-0.5, 0, 1}), "antiparallel, overlapping span", 0.7);
  expectWorld(x, cap({2, 0, 1}, {3, 0, 1}), "parallel, disjoint span", std::hypot(1.0, 1.0) - 0.3);
  expectWorld(x, cap({-3, 0, 1}, {-2, 0, 1}), "parallel, disjoint span before", std::hypot(1.0, 1.0) - 0.3);
  expectWorld(x, cap({2, 0, 0}, {4, 0, 0}), "collinear, disjoint", 0.7);
  expectWorld(x, cap({0.5, 0, 0}, {4, 0, 0}), "collinear, overlapping", -0.3);
  expectWorld(x, cap({-0.5, 0, 0}, {0.5, 0, 0}), "collinear, contained", -0.3);
  expectWorld(x, cap({1.5, 1, 0}, {1.5, 3, 0}), "endpoint to endpoint", std::hypot(0.5, 1.0) - 0.3);
  expectWorld(x, cap({0.2, 1, 0}, {0.2, 3, 2}), "endpoint to interior", 0.7);
  expectWorld(x, cap({2, 1, -1}, {2, 1, 1}), "interior to endpoint", std::hypot(1.0, 1.0) - 0.3);
  expectWorld(x, cap({1.05, 0.1, 0}, {1.05, 0.1, 2}), "endpoints, overlapping", std::hypot(0.05, 0.1) - 0.3);
}

// Random pairs of every kind, random placements; a fifth are (nearly) parallel.
TEST(ShapeDistance, RandomPairs) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  auto vec = [&] { return Vector3d(u(rng), u(rng), u(rng)); };
  for (int k = 0; k < 300; ++k) {
    SE3<double> oMa = placement(vec(), 3 * u(rng), vec()), oMb = placement(vec(), 3 * u(rng), vec());
    Shape A = Shape::capsule(vec(), vec(), 0.1), B = Shape::capsule(vec(), vec(), 0.2);
    if (k % 5 == 0) {  // B parallel to A in the world, up to an angle of 0 .. 1e-5
      Vector3d da = oMa.rotation * (A.b - A.a);
      Vector3d db = da * (2 * u(rng));
      if (k % 10 == 0) db += vec().cross(da) * std::pow(10.0, -5 - 6 * std::abs(u(rng)));
      B.b = B.a + oMb.rotation.transpose() * db;
    }
    if (k % 7 == 1) A.kind = Shape::Kind::Sphere;
    if (k % 11 == 2) B.kind = Shape::Kind::Sphere;
    expectMatchesBruteForce(A, oMa, B, oMb, "random pair " + std::to_string(k));
  }
}

}  // namespace
}  // namespace robodiff
