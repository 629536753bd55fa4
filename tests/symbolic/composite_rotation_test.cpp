// A composite inertia moved to its parent's frame by a revolute joint about a coordinate
// axis (crbaJointFrames): rotated about the axis with the angle's products c^2, s^2 and cs,
// then by a placement that only permutes axes. It must equal the transform by the joint's
// whole placement and, traced, take fewer operations than it.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/crba.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::symbolic {
namespace {

InertiaSum<double> randomComposite(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Matrix3d a = Eigen::Matrix3d::NullaryExpr([&] { return u(rng); });
  InertiaSum<double> y;
  y.mass = 3.0 + u(rng);
  y.h = Eigen::Vector3d(u(rng), u(rng), u(rng));
  y.rotational = a * a.transpose() + Eigen::Matrix3d::Identity();
  return y;
}

// A revolute joint about coordinate axis k, its placement turned a quarter about x (axes
// swapped and one flipped) and shifted along one of them.
Joint revoluteAbout(int k) {
  Joint joint;
  joint.axis_kind = k == 0 ? AxisKind::X : k == 1 ? AxisKind::Y : AxisKind::Z;
  joint.axis = Eigen::Vector3d::Unit(k);
  joint.placement.rotation << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  joint.placement.translation = Eigen::Vector3d(0.0, -0.316, 0.0);  // as the Panda's elbow
  return joint;
}

double distance(const InertiaSum<double>& a, const InertiaSum<double>& b) {
  return std::abs(a.mass - b.mass) + (a.h - b.h).norm() + (a.rotational - b.rotational).norm();
}

TEST(CompositeRotation, EqualsTheTransformByTheJointsPlacement) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-4.0, 4.0);
  for (int k = 0; k < 3; ++k) {
    const Joint joint = revoluteAbout(k);
    for (int trial = 0; trial < 50; ++trial) {
      const InertiaSum<double> y = randomComposite(rng);
      const Eigen::VectorXd q = Eigen::VectorXd::Constant(1, angle(rng));
      const InertiaSum<double> expected = y.transformedBy(jointPlacement<double>(joint, q));
      const InertiaSum<double> got =
          y.rotatedAboutAxis(k, std::cos(q[0]), std::sin(q[0])).transformedBy(joint.placement);
      EXPECT_LT(distance(got, expected), 1e-13) << "axis " << k << ", q " << q[0];
    }
  }
}

// Operations of a composite moved by the joint, either way: a leaf's constant composite,
// or one with variable entries (one a child's transform has added to).
std::size_t tracedOperations(const Joint& joint, bool constant_composite, bool about_the_axis_first) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> x = tracer.addInputs("x", 11);
  InertiaSum<Sym> y;
  if (constant_composite) {
    std::mt19937 rng(5);
    const InertiaSum<double> leaf = randomComposite(rng);
    y.mass = leaf.mass;
    y.h = leaf.h.cast<Sym>();
    y.rotational = leaf.rotational.cast<Sym>();
  } else {
    y.mass = x[0];
    y.h = x.segment<3>(1);
    for (int r = 0, i = 4; r < 3; ++r)
      for (int c = r; c < 3; ++c, ++i) y.rotational(r, c) = y.rotational(c, r) = x[i];
  }
  const VecX<Sym> q = x.segment<1>(10);
  const InertiaSum<Sym> out =
      about_the_axis_first
          ? y.rotatedAboutAxis(2, Sym(math::cos(q[0])), Sym(math::sin(q[0]))).transformedBy(asScalar<Sym>(joint.placement))
          : y.transformedBy(jointPlacement<Sym>(joint, q));
  VecX<Sym> all(13);
  all << out.h, Eigen::Map<const VecX<Sym>>(out.rotational.data(), 9), out.mass;
  return coneSize(graph, tracer.outputs(all)).operations;
}

TEST(CompositeRotation, TracedAboutTheAxisFirstItTakesFewerOperations) {
  const Joint joint = revoluteAbout(2);
  for (bool constant : {true, false}) {
    const std::size_t whole = tracedOperations(joint, constant, false);
    const std::size_t axis_first = tracedOperations(joint, constant, true);
    EXPECT_LT(axis_first, whole) << (constant ? "a leaf's composite" : "a composite of variables");
    RecordProperty(constant ? "operations_leaf" : "operations_variable",
                   std::to_string(whole) + " -> " + std::to_string(axis_first));
  }
}

}  // namespace
}  // namespace robodiff::symbolic
