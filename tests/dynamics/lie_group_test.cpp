// integrateConfiguration / differenceConfiguration in double: agreement with
// robodiff::integrate (up to the quaternion's sign) and the round trips, from zero
// motion through the series/exact switch to large rotations.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/lie_group.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff {
namespace {

Model floatingChain() {
  GeneratorOptions options;
  options.kind = RobotKind::Chain;
  options.joints = 5;
  options.seed = 3;
  options.prismatic_fraction = 0.4;
  options.continuous_fraction = 0.2;
  return loadUrdfString(generateRobotUrdf(options), RootJoint::FreeFlyer, "chain5");
}

Model fixedChain() {
  GeneratorOptions options;
  options.kind = RobotKind::Chain;
  options.joints = 4;
  options.seed = 8;
  options.prismatic_fraction = 0.5;
  return loadUrdfString(generateRobotUrdf(options), RootJoint::Fixed, "chain4");
}

const Joint& root(const Model& model) { return model.joints.front(); }

// A random tangent vector with the free-flyer's angular part of norm `angle`.
Eigen::VectorXd randomTangent(const Model& model, std::mt19937_64& rng, double angle) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd d(model.nv);
  for (int i = 0; i < model.nv; ++i) d[i] = u(rng);
  const Joint& j = root(model);
  if (j.type == JointType::FreeFlyer) {
    Eigen::Vector3d w(u(rng), u(rng), u(rng));
    d.segment<3>(j.idx_v + 3) = angle * w.normalized();
  }
  return d;
}

Eigen::Matrix3d rotationOf(const Eigen::VectorXd& q, int iq) {
  return quaternionRotation<double>(q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]);
}

// Equal configurations, the free-flyer's quaternion up to its sign.
::testing::AssertionResult sameConfiguration(const Model& model, const Eigen::VectorXd& a,
                                             const Eigen::VectorXd& b, double tol) {
  Eigen::VectorXd b2 = b;
  for (const Joint& j : model.joints) {
    if (j.type != JointType::FreeFlyer) continue;
    if (a.segment<4>(j.idx_q + 3).dot(b.segment<4>(j.idx_q + 3)) < 0) b2.segment<4>(j.idx_q + 3) *= -1;
    const double rot = (rotationOf(a, j.idx_q) - rotationOf(b, j.idx_q)).norm();
    if (rot > tol) return ::testing::AssertionFailure() << "rotations differ by " << rot;
  }
  const double err = (a - b2).lpNorm<Eigen::Infinity>();
  if (err > tol)
    return ::testing::AssertionFailure() << "differ by " << err << "\n" << a.transpose() << "\n" << b.transpose();
  return ::testing::AssertionSuccess();
}

const double kAngles[] = {0.0, 1e-12, 1e-9, 1e-5, 0.0316, 0.0317, 0.3, 1.5, 3.1, 4.0, 10.0, 40.0};

TEST(IntegrateConfiguration, MatchesIntegrate) {
  for (const Model& model : {floatingChain(), fixedChain()}) {
    std::mt19937_64 rng(1);
    for (double angle : kAngles) {
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd q = randomConfiguration(model, rng);
        const Eigen::VectorXd dq = randomTangent(model, rng, angle);
        const Eigen::VectorXd out = integrateConfiguration<double>(model, q, dq);
        // robodiff::integrate's (1 - cos t) / t^2 loses digits for small t (error ~ 1e-16 / t).
        const double tol = 1e-12 + (angle > 0 ? 4e-16 / angle : 0.0);
        EXPECT_TRUE(sameConfiguration(model, out, integrate(model, q, dq), tol)) << model.name << " |w| = " << angle;
        if (model.root == RootJoint::FreeFlyer) {
          EXPECT_NEAR(out.segment<4>(root(model).idx_q + 3).norm(), 1.0, 1e-14);
        }
      }
    }
  }
}

TEST(IntegrateConfiguration, ZeroMotionIsIdentityAndSmallStepsAreContinuous) {
  const Model model = floatingChain();
  std::mt19937_64 rng(2);
  const Eigen::VectorXd q = randomConfiguration(model, rng);
  EXPECT_EQ(integrateConfiguration<double>(model, q, Eigen::VectorXd::Zero(model.nv)), q);
  // Across the switch between series and exact forms the result moves continuously.
  const Eigen::VectorXd dir = randomTangent(model, rng, 1.0);
  const double t = std::sqrt(lie_group_detail::kSmallAngle2);
  const Eigen::VectorXd below = integrateConfiguration<double>(model, q, (t * (1 - 1e-12)) * dir);
  const Eigen::VectorXd above = integrateConfiguration<double>(model, q, (t * (1 + 1e-12)) * dir);
  EXPECT_LT((below - above).lpNorm<Eigen::Infinity>(), 1e-13);
}

TEST(DifferenceConfiguration, InvertsIntegrate) {
  for (const Model& model : {floatingChain(), fixedChain()}) {
    std::mt19937_64 rng(3);
    for (double angle : {0.0, 1e-12, 1e-9, 1e-6, 0.0316, 0.0317, 0.5, 2.0, 3.0, 3.14}) {
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::VectorXd q = randomConfiguration(model, rng);
        const Eigen::VectorXd d = randomTangent(model, rng, angle);
        const Eigen::VectorXd back = differenceConfiguration<double>(model, q, integrateConfiguration<double>(model, q, d));
        EXPECT_LT((back - d).lpNorm<Eigen::Infinity>(), 1e-12) << model.name << " |w| = " << angle;
      }
    }
    const Eigen::VectorXd q = randomConfiguration(model, rng);
    EXPECT_LT(differenceConfiguration<double>(model, q, q).lpNorm<Eigen::Infinity>(), 1e-15);
  }
}

TEST(DifferenceConfiguration, IntegrateInvertsIt) {
  const Model model = floatingChain();
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::VectorXd q0 = randomConfiguration(model, rng), q1 = randomConfiguration(model, rng);
    const Eigen::VectorXd d = differenceConfiguration<double>(model, q0, q1);
    EXPECT_LE(d.segment<3>(root(model).idx_v + 3).norm(), M_PI + 1e-12);  // the shorter way
    EXPECT_TRUE(sameConfiguration(model, integrateConfiguration<double>(model, q0, d), q1, 1e-12));
    EXPECT_TRUE(sameConfiguration(model, integrate(model, q0, d), q1, 1e-12));
  }
}

TEST(DifferenceConfiguration, IgnoresTheQuaternionSign) {
  const Model model = floatingChain();
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q0 = randomConfiguration(model, rng), q1 = randomConfiguration(model, rng);
    Eigen::VectorXd q0n = q0, q1n = q1;
    q0n.segment<4>(3) *= -1;
    q1n.segment<4>(3) *= -1;
    const Eigen::VectorXd d = differenceConfiguration<double>(model, q0, q1);
    EXPECT_LT((differenceConfiguration<double>(model, q0n, q1) - d).lpNorm<Eigen::Infinity>(), 1e-12);
    EXPECT_LT((differenceConfiguration<double>(model, q0, q1n) - d).lpNorm<Eigen::Infinity>(), 1e-12);
  }
}

TEST(ConfigurationOperations, RejectWrongSizes) {
  const Model model = floatingChain();
  const Eigen::VectorXd q = neutralConfiguration(model);
  EXPECT_THROW(integrateConfiguration<double>(model, q, Eigen::VectorXd::Zero(model.nq)), std::invalid_argument);
  EXPECT_THROW(differenceConfiguration<double>(model, q, Eigen::VectorXd::Zero(model.nv)), std::invalid_argument);
}

}  // namespace
}  // namespace robodiff
