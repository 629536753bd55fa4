// shapeDistance traced on Sym: one graph per pair of shapes is valid at every placement
// (it equals the double version, parallel segments included), and its Jacobian matches
// central finite differences and the envelope rule normal . (d c_a - d c_b).
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "robodiff/dynamics/shape_distance.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::symbolic {
namespace {

using Eigen::Vector3d;

// A placement from 7 parameters at x[o..o+6]: translation, then a unit quaternion (x, y, z, w).
template <class S, class V> SE3<S> quaternionPlacement(const V& x, int o) {
  return {quaternionRotation<S>(x[o + 3], x[o + 4], x[o + 5], x[o + 6]), Vec3<S>(x[o], x[o + 1], x[o + 2])};
}

Eigen::VectorXd randomPlacements(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd x(14);
  for (int o : {0, 7}) {
    x.segment<3>(o) = Vector3d(u(rng), u(rng), u(rng));
    x.segment<4>(o + 3) = Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized();
  }
  return x;
}

// distance, point_a, point_b, normal as 10 numbers.
template <class S> VecX<S> flatten(const ShapeDistance<S>& r) {
  VecX<S> out(10);
  out << r.distance, r.point_a, r.point_b, r.normal;
  return out;
}

struct Pair {
  std::string label;
  Shape a, b;
};

std::vector<Pair> pairs() {
  Shape capsule_a = Shape::capsule({-0.3, 0.1, 0}, {0.4, 0, 0.2}, 0.1);
  Shape capsule_b = Shape::capsule({0.1, -0.5, 0.3}, {0, 0.4, -0.1}, 0.2);
  return {{"sphere-sphere", Shape::sphere({0.1, 0.2, 0.3}, 0.1), Shape::sphere({-0.2, 0, 0.1}, 0.3)},
          {"sphere-capsule", Shape::sphere({0.1, 0.2, 0.3}, 0.1), capsule_b},
          {"capsule-sphere", capsule_a, Shape::sphere({-0.2, 0, 0.1}, 0.3)},
          {"capsule-capsule", capsule_a, capsule_b},
          {"point capsule-capsule", Shape::capsule({0.2, 0.2, 0.2}, {0.2, 0.2, 0.2}, 0.1), capsule_b}};
}

std::vector<double> values(const Eigen::VectorXd& x) { return {x.data(), x.data() + x.size()}; }

TEST(ShapeDistanceTrace, EqualsDoubleAtRandomPlacements) {
  std::mt19937_64 rng(5);
  for (const Pair& p : pairs()) {
    SCOPED_TRACE(p.label);
    Graph graph;
    Tracer tracer(graph);
    VecX<Sym> x = tracer.addInputs("x", 14);
    std::vector<NodeId> out = tracer.outputs(
        flatten(shapeDistance(p.a, quaternionPlacement<Sym>(x, 0), p.b, quaternionPlacement<Sym>(x, 7))));
    for (int k = 0; k < 50; ++k) {
      Eigen::VectorXd xd = randomPlacements(rng);
      if (k % 5 == 0) xd.segment<4>(10) = xd.segment<4>(3);  // same rotation
      std::vector<double> traced = graph.evaluate(out, values(xd));
      Eigen::VectorXd expected = flatten(
          shapeDistance(p.a, quaternionPlacement<double>(xd, 0), p.b, quaternionPlacement<double>(xd, 7)));
      for (int i = 0; i < 10; ++i) EXPECT_NEAR(traced[i], expected[i], 1e-12) << "placement " << k << " entry " << i;
    }
  }
}

// Parallel segments (same rotation, parallel in their frames) take the parallel branch of
// the same graph; the values equal the double version.
TEST(ShapeDistanceTrace, ParallelSegmentsInTheSameGraph) {
  Shape a = Shape::capsule({-1, 0, 0}, {1, 0, 0}, 0.1), b = Shape::capsule({0.5, 0.3, 0}, {2, 0.3, 0}, 0.1);
  Graph graph;
  Tracer tracer(graph);
  VecX<Sym> x = tracer.addInputs("x", 14);
  std::vector<NodeId> out =
      tracer.outputs(flatten(shapeDistance(a, quaternionPlacement<Sym>(x, 0), b, quaternionPlacement<Sym>(x, 7))));
  std::mt19937_64 rng(9);
  for (int k = 0; k < 20; ++k) {
    Eigen::VectorXd xd = randomPlacements(rng);
    xd.segment<4>(10) = xd.segment<4>(3);
    std::vector<double> traced = graph.evaluate(out, values(xd));
    Eigen::VectorXd expected =
        flatten(shapeDistance(a, quaternionPlacement<double>(xd, 0), b, quaternionPlacement<double>(xd, 7)));
    for (int i = 0; i < 10; ++i) {
      EXPECT_TRUE(std::isfinite(traced[i]));
      EXPECT_NEAR(traced[i], expected[i], 1e-12) << "placement " << k << " entry " << i;
    }
  }
}

// Derivatives w.r.t. 8 placement parameters theta: for each frame a translation (3) and
// an angle (1) about a fixed axis, applied on top of a base placement.
struct Placements {
  SE3<double> base_a, base_b;
  Vector3d axis_a, axis_b;

  template <class S, class V> SE3<S> frame(const V& th, int o, const SE3<double>& base, const Vector3d& axis) const {
    Vec3<S> t(th[o], th[o + 1], th[o + 2]);
    return {axisAngleRotation<S>(axis, th[o + 3]) * base.rotation.cast<S>(), base.translation.cast<S>() + t};
  }
  template <class S, class V> SE3<S> a(const V& th) const { return frame<S>(th, 0, base_a, axis_a); }
  template <class S, class V> SE3<S> b(const V& th) const { return frame<S>(th, 4, base_b, axis_b); }
};

struct DerivativeCase {
  std::string label;
  Shape a, b;     // in world coordinates at theta = 0
  bool rotations;  // false: rotating switches features (parallel segments), translations only
};

Shape inFrame(Shape s, const SE3<double>& oMf) {
  s.a = oMf.actInv(s.a);
  s.b = oMf.actInv(s.b);
  return s;
}

std::vector<DerivativeCase> derivativeCases() {
  Shape x = Shape::capsule({-1, 0, 0}, {1, 0, 0}, 0.1);
  auto cap = [](Vector3d a, Vector3d b) { return Shape::capsule(a, b, 0.2); };
  return {{"sphere-sphere", Shape::sphere({0.1, 0.2, 0.3}, 0.1), Shape::sphere({-0.5, 0.4, 1}, 0.3), true},
          {"sphere-capsule interior", Shape::sphere({0.3, 1, 0.5}, 0.1), x, true},
          {"sphere-capsule endpoint", Shape::sphere({1.6, 1, 0.5}, 0.1), x, true},
          {"capsule-capsule crossing", x, cap({0.3, -1, 1}, {0.2, 1, 1.3}), true},
          {"capsule-capsule crossing, overlapping", x, cap({0.3, -1, 0.1}, {0.2, 1, 0.15}), true},
          {"capsule-capsule endpoint to interior", x, cap({0.2, 1, 0}, {0.2, 3, 2}), true},
          {"capsule-capsule endpoint to endpoint", x, cap({1.5, 1, 0}, {1.7, 3, 0.5}), true},
          {"capsule-capsule parallel", x, cap({-0.5, 0.3, 1}, {2, 0.3, 1}), false},
          {"capsule-capsule collinear", x, cap({2, 0, 0}, {4, 0, 0}), false}};
}

TEST(ShapeDistanceTrace, JacobianMatchesFiniteDifferencesAndEnvelopeRule) {
  Placements pl{{axisAngleRotation<double>(Vector3d(1, 2, 3).normalized(), 0.7), Vector3d(0.3, -0.2, 0.5)},
                {axisAngleRotation<double>(Vector3d(-2, 1, 0.5).normalized(), -1.1), Vector3d(-0.4, 0.6, 0.1)},
                Vector3d(0.3, -1, 0.2).normalized(),
                Vector3d(1, 0.5, -0.7).normalized()};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  for (const DerivativeCase& c : derivativeCases()) {
    SCOPED_TRACE(c.label);
    const Shape A = inFrame(c.a, pl.base_a), B = inFrame(c.b, pl.base_b);
    Eigen::VectorXd th0(8);
    for (int i = 0; i < 8; ++i) th0[i] = (i % 4 == 3 && !c.rotations) ? 0.0 : u(rng);
    auto f = [&](const Eigen::VectorXd& th) { return shapeDistance(A, pl.a<double>(th), B, pl.b<double>(th)); };
    const ShapeDistance<double> r0 = f(th0);
    // The nearest points at th0, held fixed on their bodies.
    const Vector3d xa = pl.a<double>(th0).actInv(r0.point_a), xb = pl.b<double>(th0).actInv(r0.point_b);

    Graph graph;
    Tracer tracer(graph);
    VecX<Sym> th = tracer.addInputs("theta", 8);
    std::vector<NodeId> out{tracer.output(shapeDistanceValue(A, pl.a<Sym>(th), B, pl.b<Sym>(th)))};
    Vec3<Sym> fixed_a = pl.a<Sym>(th).act(xa.cast<Sym>()), fixed_b = pl.b<Sym>(th).act(xb.cast<Sym>());
    for (NodeId id : tracer.outputs(fixed_a)) out.push_back(id);
    for (NodeId id : tracer.outputs(fixed_b)) out.push_back(id);
    Jacobian jac = jacobian(graph, out, tracer.indices({"theta"}));
    std::vector<double> jv = graph.evaluate(jac.entries, values(th0));
    Eigen::Map<const Eigen::Matrix<double, 7, 8, Eigen::RowMajor>> J(jv.data());

    const Eigen::Matrix<double, 1, 8> envelope = r0.normal.transpose() * (J.middleRows<3>(1) - J.middleRows<3>(4));
    const double h = 1e-6;
    for (int i = 0; i < 8; ++i) {
      // The envelope rule holds for every parameter, the graph derivative being one-sided
      // where a feature switches.
      EXPECT_NEAR(J(0, i), envelope(i), 1e-9) << "parameter " << i;
      if (i % 4 == 3 && !c.rotations) continue;
      Eigen::VectorXd plus = th0, minus = th0;
      plus[i] += h;
      minus[i] -= h;
      EXPECT_NEAR(J(0, i), (f(plus).distance - f(minus).distance) / (2 * h), 1e-7) << "parameter " << i;
    }
    // Translating a frame moves the distance along the normal.
    EXPECT_LT((J.block<1, 3>(0, 0).transpose() - r0.normal).norm(), 1e-9);
    EXPECT_LT((J.block<1, 3>(0, 4).transpose() + r0.normal).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace robodiff::symbolic
