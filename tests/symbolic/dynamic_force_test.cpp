// Inertia::dynamicForce, each body's I a + v x* (I v) as RNEA and ABA compute it: summed at
// the centre of mass and moved to the origin. It must equal the two products and the cross
// product it replaces, and, traced with a body's constant inertia, take fewer operations.
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/joint.hpp"
#include "robodiff/spatial/inertia.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::symbolic {
namespace {

// A body with every inertial term nonzero: an off-centre lever and a full tensor.
Inertia<double> generalBody(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Matrix3d a = Eigen::Matrix3d::NullaryExpr([&] { return u(rng); });
  return {2.0 + u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)), a * a.transpose() + Eigen::Matrix3d::Identity()};
}

Motion<double> randomMotion(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  return {Eigen::Vector3d(u(rng), u(rng), u(rng)), Eigen::Vector3d(u(rng), u(rng), u(rng))};
}

TEST(DynamicForce, EqualsTheInertiaProductsAndTheCrossProduct) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const Inertia<double> body = generalBody(rng);
    const Motion<double> v = randomMotion(rng), a = randomMotion(rng);
    const Force<double> expected = body * a + v.cross(body * v);
    const Force<double> f = body.dynamicForce(v, a);
    const double scale = 1.0 + expected.linear.norm() + expected.angular.norm();
    EXPECT_LT((f.linear - expected.linear).norm(), 1e-13 * scale) << "trial " << trial;
    EXPECT_LT((f.angular - expected.angular).norm(), 1e-13 * scale) << "trial " << trial;
  }
}

// Operations of the traced force of one body with constant inertia, at variable v and a
// (or a = 0, ABA's bias force).
std::size_t tracedOperations(const Inertia<double>& body, bool with_acceleration, bool summed_at_com) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> x = tracer.addInputs("x", 12);
  const Motion<Sym> v{x.segment<3>(0), x.segment<3>(3)};
  Motion<Sym> a;
  if (with_acceleration) a = {x.segment<3>(6), x.segment<3>(9)};
  const auto& I = asScalar<Sym>(body);
  const Force<Sym> f = summed_at_com ? I.dynamicForce(v, a) : I * a + v.cross(I * v);
  return coneSize(graph, tracer.outputs(f.toVector())).operations;
}

TEST(DynamicForce, TracedWithABodysConstantsItTakesFewerOperations) {
  std::mt19937 rng(5);
  const Inertia<double> body = generalBody(rng);
  for (bool with_acceleration : {true, false}) {
    const std::size_t products = tracedOperations(body, with_acceleration, false);
    const std::size_t at_com = tracedOperations(body, with_acceleration, true);
    EXPECT_LT(at_com, products) << (with_acceleration ? "I a + v x* I v" : "v x* I v");
    RecordProperty(with_acceleration ? "operations_rnea" : "operations_bias",
                   std::to_string(products) + " -> " + std::to_string(at_com));
  }
}

}  // namespace
}  // namespace robodiff::symbolic
