// The portable model arithmetic (core/model/src/portable_geometry.hpp) against Eigen's
// and the spatial library's formulas: the same quantities to rounding, and inertias
// exactly symmetric.
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "../../core/model/src/portable_geometry.hpp"

namespace robodiff {
namespace {

constexpr double kPortableGeometryTol = 1e-14;

Mat3<double> portableGeometryRandomInertia(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3<double> a;
  for (int i = 0; i < 9; ++i) a(i) = u(rng);
  const Mat3<double> i = a * a.transpose() + 0.1 * Mat3<double>::Identity();
  return 0.5 * (i + i.transpose());  // exactly symmetric, as a URDF's
}

TEST(PortableGeometry, RpyRotationIsYawPitchRoll) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> angle(-4, 4);
  for (int i = 0; i < 1000; ++i) {
    const double r = angle(rng), p = angle(rng), y = angle(rng);
    const Mat3<double> expected = (Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(p, Eigen::Vector3d::UnitY()) *
                                   Eigen::AngleAxisd(r, Eigen::Vector3d::UnitX()))
                                      .toRotationMatrix();
    EXPECT_TRUE(portable::rpyRotation(r, p, y).isApprox(expected, kPortableGeometryTol)) << r << " " << p << " " << y;
  }
}

TEST(PortableGeometry, InertiasMoveAndMergeAsTheSpatialFormulas) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-1, 1), mass(0.1, 5);
  for (int i = 0; i < 200; ++i) {
    const SE3<double> m{portable::rpyRotation(u(rng), u(rng), u(rng)), Vec3<double>(u(rng), u(rng), u(rng))};
    const Inertia<double> a{mass(rng), Vec3<double>(u(rng), u(rng), u(rng)), portableGeometryRandomInertia(rng)};
    const Inertia<double> b{mass(rng), Vec3<double>(u(rng), u(rng), u(rng)), portableGeometryRandomInertia(rng)};

    const Inertia<double> moved = portable::transformInertia(a, m), expected_moved = a.transformedBy(m);
    EXPECT_EQ(moved.mass, a.mass);
    EXPECT_TRUE(moved.lever.isApprox(expected_moved.lever, kPortableGeometryTol));
    EXPECT_TRUE(moved.inertia.isApprox(expected_moved.inertia, kPortableGeometryTol));
    EXPECT_EQ(moved.inertia, moved.inertia.transpose()) << "not exactly symmetric";

    const Inertia<double> merged = portable::mergeInertias(a, b), expected_merged = a + b;
    EXPECT_DOUBLE_EQ(merged.mass, expected_merged.mass);
    EXPECT_TRUE(merged.lever.isApprox(expected_merged.lever, kPortableGeometryTol));
    EXPECT_TRUE(merged.inertia.isApprox(expected_merged.inertia, kPortableGeometryTol));
    EXPECT_EQ(merged.inertia, merged.inertia.transpose()) << "not exactly symmetric";

    const SE3<double> composed = portable::compose(m, m), expected_composed = m * m;
    EXPECT_TRUE(composed.rotation.isApprox(expected_composed.rotation, kPortableGeometryTol));
    EXPECT_TRUE(composed.translation.isApprox(expected_composed.translation, kPortableGeometryTol));
  }
}

TEST(PortableGeometry, MasslessBodiesKeepTheirRotationalInertiasAndAxesNormalise) {
  const Inertia<double> a{0.0, Vec3<double>(1, 2, 3), Mat3<double>::Identity()};
  const Inertia<double> b{0.0, Vec3<double>(-1, 0, 0), 2 * Mat3<double>::Identity()};
  const Inertia<double> merged = portable::mergeInertias(a, b);
  EXPECT_EQ(merged.mass, 0.0);
  EXPECT_EQ(merged.lever, Vec3<double>::Zero());
  EXPECT_EQ(merged.inertia, 3 * Mat3<double>::Identity());

  EXPECT_EQ(portable::normalized(Vec3<double>(0, 0, 2)), Vec3<double>(0, 0, 1));
  EXPECT_TRUE(portable::normalized(Vec3<double>(1, 2, 2)).isApprox(Vec3<double>(1, 2, 2) / 3.0, 1e-15));
  EXPECT_EQ(portable::normalized(Vec3<double>::Zero()), Vec3<double>::Zero());
}

}  // namespace
}  // namespace robodiff
