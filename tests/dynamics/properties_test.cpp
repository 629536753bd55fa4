// Checks that need no external reference, on the project's own generated robots (fixed
// and floating bases, prismatic and continuous joints, unaligned axes, merged links):
// the algorithms against each other, against finite differences and against physics.
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/robot_cases.hpp"

namespace robodiff {
namespace {

using testing::matricesAgree;

using Case = testing::RobotCase;

std::vector<Case> cases() {
  GeneratorOptions chain;
  chain.kind = RobotKind::Chain;
  chain.joints = 9;
  chain.seed = 11;
  chain.prismatic_fraction = 0.25;
  chain.continuous_fraction = 0.25;
  GeneratorOptions quadruped;
  quadruped.kind = RobotKind::Tree;
  quadruped.tree = "quadruped";
  quadruped.seed = 5;
  GeneratorOptions humanoid = quadruped;
  humanoid.tree = "humanoid";
  humanoid.seed = 6;
  humanoid.prismatic_fraction = 0.1;
  return {{"chain9_fixed", chain, RootJoint::Fixed},
          {"chain9_floating", chain, RootJoint::FreeFlyer},
          {"quadruped_floating", quadruped, RootJoint::FreeFlyer},
          {"humanoid_fixed", humanoid, RootJoint::Fixed},
          {"humanoid_floating", humanoid, RootJoint::FreeFlyer}};
}

class Properties : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    model = GetParam().load();
  }
  struct State {
    Eigen::VectorXd q, v, a;
  };
  State randomState(std::uint64_t seed) const {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-2, 2);
    State s{randomConfiguration(model, rng), Eigen::VectorXd(model.nv), Eigen::VectorXd(model.nv)};
    for (int i = 0; i < model.nv; ++i) s.v[i] = u(rng), s.a[i] = u(rng);
    return s;
  }
  Model model;
};

constexpr int kSamples = 5;

TEST_P(Properties, MassMatrixIsSymmetricPositiveDefinite) {
  Data<double> data(model);
  for (int s = 0; s < kSamples; ++s) {
    Eigen::MatrixXd M = crba(model, data, randomState(s).q);
    EXPECT_TRUE(matricesAgree(M, M.transpose(), 1e-14));
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  }
}

// The two forms of CRBA (joint frames, world frame) are the same M, and give the same M^-1.
TEST_P(Properties, MassMatrixInJointFramesEqualsItInTheWorldFrame) {
  Data<double> data(model);
  for (int s = 0; s < kSamples; ++s) {
    const Eigen::VectorXd q = randomState(s).q;
    const Eigen::MatrixXd M = crbaJointFrames(model, data, q);
    EXPECT_TRUE(matricesAgree(crbaWorldFrame(model, data, q), M, 1e-12));
    const Eigen::MatrixXd Minv = computeMinverse(model, data, q, CrbaFrame::Joint);
    EXPECT_TRUE(matricesAgree(computeMinverse(model, data, q, CrbaFrame::World), Minv, 1e-9));
  }
}

TEST_P(Properties, RneaIsMassMatrixTimesAPlusNonLinearEffects) {
  Data<double> data(model);
  for (int s = 0; s < kSamples; ++s) {
    State x = randomState(s);
    Eigen::VectorXd tau = rnea(model, data, x.q, x.v, x.a);
    Eigen::MatrixXd M = crba(model, data, x.q);
    Eigen::VectorXd nle = nonLinearEffects(model, data, x.q, x.v);
    EXPECT_TRUE(matricesAgree(M * x.a + nle, tau, 1e-11));
  }
}

TEST_P(Properties, GravityIsRneaAtRest) {
  Data<double> data(model);
  for (int s = 0; s < kSamples; ++s) {
    State x = randomState(s);
    Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.nv);
    Eigen::VectorXd expected = rnea(model, data, x.q, zero, zero);
    EXPECT_TRUE(matricesAgree(computeGeneralizedGravity(model, data, x.q), expected, 1e-12));
  }
}

TEST_P(Properties, AbaInvertsRnea) {
  Data<double> data(model);
  for (int s = 0; s < kSamples; ++s) {
    State x = randomState(s);
    Eigen::VectorXd tau = rnea(model, data, x.q, x.v, x.a);
    EXPECT_TRUE(matricesAgree(aba(model, data, x.q, x.v, tau), x.a, 1e-9));
  }
}

TEST_P(Properties, ForwardDynamicsByFactorsIsAba) {
  Data<double> data(model);
  for (int s = 0; s < kSamples; ++s) {
    State x = randomState(s);
    const Eigen::VectorXd tau = rnea(model, data, x.q, x.v, x.a);
    const Eigen::VectorXd by_factors = forwardDynamicsByFactors(model, data, x.q, x.v, tau);
    EXPECT_TRUE(matricesAgree(by_factors, aba(model, data, x.q, x.v, tau), 1e-9));
    EXPECT_TRUE(matricesAgree(by_factors, x.a, 1e-9));
  }
}

TEST_P(Properties, MinverseInvertsTheMassMatrix) {
  // The tree-structured factorisation against a dense LU inverse, and against ABA:
  // M^-1 (tau - nle) is the forward dynamics.
  Data<double> data(model);
  for (int s = 0; s < kSamples; ++s) {
    State x = randomState(s);
    const Eigen::MatrixXd M = crba(model, data, x.q);
    const Eigen::MatrixXd Minv = computeMinverse(model, data, x.q);
    EXPECT_TRUE(matricesAgree(Minv, M.inverse(), 1e-9));
    EXPECT_TRUE(matricesAgree(Minv, Minv.transpose(), 0.0));
    const Eigen::VectorXd tau = rnea(model, data, x.q, x.v, x.a);
    const Eigen::VectorXd nle = nonLinearEffects(model, data, x.q, x.v);
    EXPECT_TRUE(matricesAgree(Minv * (tau - nle), aba(model, data, x.q, x.v, tau), 1e-9));
  }
}

TEST_P(Properties, AbaWithExternalForcesInvertsRneaWithThem) {
  Data<double> data(model);
  State x = randomState(3);
  std::vector<Force<double>> fext(model.njoints());
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-5, 5);
  for (auto& f : fext) f = Force<double>{Eigen::Vector3d(u(rng), u(rng), u(rng)), Eigen::Vector3d(u(rng), u(rng), u(rng))};
  Eigen::VectorXd tau = rnea(model, data, x.q, x.v, x.a, &fext);
  EXPECT_TRUE(matricesAgree(aba(model, data, x.q, x.v, tau, &fext), x.a, 1e-9));
}

// An external force f on joint j's body (in j's frame) changes tau by -J_j^T f, with
// J_j the LOCAL Jacobian of j's frame.
TEST_P(Properties, ExternalForceEntersThroughTheJacobianTranspose) {
  Data<double> data(model);
  State x = randomState(4);
  const int j = model.njoints() - 1;
  std::vector<Force<double>> fext(model.njoints());
  fext[j] = Force<double>{Eigen::Vector3d(1.5, -2.0, 0.7), Eigen::Vector3d(-0.3, 0.9, 2.2)};
  Eigen::VectorXd without = rnea(model, data, x.q, x.v, x.a);
  Eigen::VectorXd with = rnea(model, data, x.q, x.v, x.a, &fext);
  Matrix6X<double> J = computeFrameJacobian(model, data, x.q, model.frameIndex(model.joints[j].name), ReferenceFrame::Local);
  EXPECT_TRUE(matricesAgree(with, without - J.transpose() * fext[j].toVector(), 1e-11));
}

TEST_P(Properties, RegressorTimesParametersIsRnea) {
  Data<double> data(model);
  const Eigen::VectorXd pi = inertialParameters(model);
  for (int s = 0; s < kSamples; ++s) {
    State x = randomState(s);
    Eigen::VectorXd tau = rnea(model, data, x.q, x.v, x.a);
    EXPECT_TRUE(matricesAgree(jointTorqueRegressor(model, data, x.q, x.v, x.a) * pi, tau, 1e-11));
  }
}

// Frame Jacobians against central differences of the frame placement along q (+) h e_k.
TEST_P(Properties, FrameJacobiansMatchFiniteDifferencesOfKinematics) {
  Data<double> data(model);
  const State x = randomState(7);
  const double h = 1e-6;
  for (int f = 0; f < model.nframes(); f += 3) {
    SCOPED_TRACE("frame " + model.frames[f].name);
    computeJointJacobians(model, data, x.q);
    const SE3<double> oMf = framePlacement(model, data, f);
    Matrix6X<double> fd_lwa(6, model.nv);
    for (int k = 0; k < model.nv; ++k) {
      Eigen::VectorXd dv = Eigen::VectorXd::Zero(model.nv);
      dv[k] = h;
      forwardKinematics(model, data, integrate(model, x.q, dv));
      SE3<double> plus = framePlacement(model, data, f);
      forwardKinematics(model, data, integrate(model, x.q, -dv));
      SE3<double> minus = framePlacement(model, data, f);
      Eigen::Matrix3d dR = (plus.rotation - minus.rotation) / (2 * h);
      Eigen::Matrix3d w = dR * oMf.rotation.transpose();  // skew(omega) in world axes
      fd_lwa.col(k) << (plus.translation - minus.translation) / (2 * h), w(2, 1), w(0, 2), w(1, 0);
    }
    computeJointJacobians(model, data, x.q);
    Matrix6X<double> lwa = frameJacobian(model, data, f, ReferenceFrame::LocalWorldAligned);
    EXPECT_TRUE(matricesAgree(lwa, fd_lwa, 1e-6));
    // WORLD: the same motion taken at the world origin; LOCAL: in the frame's axes.
    Matrix6X<double> world = fd_lwa;
    for (int k = 0; k < model.nv; ++k)
      world.block<3, 1>(0, k) += oMf.translation.cross(Eigen::Vector3d(fd_lwa.block<3, 1>(3, k)));
    EXPECT_TRUE(matricesAgree(frameJacobian(model, data, f, ReferenceFrame::World), world, 1e-6));
    Matrix6X<double> local(6, model.nv);
    local.topRows<3>() = oMf.rotation.transpose() * fd_lwa.topRows<3>();
    local.bottomRows<3>() = oMf.rotation.transpose() * fd_lwa.bottomRows<3>();
    EXPECT_TRUE(matricesAgree(frameJacobian(model, data, f, ReferenceFrame::Local), local, 1e-6));
  }
}

// LOCAL_WORLD_ALIGNED does not depend on where a floating base stands: the same
// Jacobian to rounding with the base a thousand kilometres away. Built from differences
// of world positions it lost ~1e-10 there (an ulp of 1e6).
TEST_P(Properties, WorldAlignedFrameJacobianDoesNotDependOnWhereTheBaseStands) {
  if (model.root != RootJoint::FreeFlyer) GTEST_SKIP() << "a fixed base cannot be moved";
  Data<double> data(model);
  State near = randomState(9), far = near;
  near.q.head<3>().setZero();
  far.q.head<3>() << 1e6, -2e6, 5e5;
  for (int f = 0; f < model.nframes(); f += 3) {
    SCOPED_TRACE("frame " + model.frames[f].name);
    forwardKinematics(model, data, near.q);
    const Matrix6X<double> at_origin = frameJacobian(model, data, f, ReferenceFrame::LocalWorldAligned);
    forwardKinematics(model, data, far.q);
    EXPECT_TRUE(matricesAgree(frameJacobian(model, data, f, ReferenceFrame::LocalWorldAligned), at_origin, 1e-14));
  }
}

// A frame's origin summed from its own joint placements (framePosition) is the
// translation of its world placement, for every frame, also with the base far away.
TEST_P(Properties, FramePositionIsTheTranslationOfTheFramesPlacement) {
  Data<double> data(model);
  for (std::uint64_t seed : {21u, 22u}) {
    State x = randomState(seed);
    if (model.root == RootJoint::FreeFlyer && seed == 22u) x.q.head<3>() << 1e3, -2e3, 5e2;
    forwardKinematics(model, data, x.q);
    for (int f = 0; f < model.nframes(); ++f) {
      SCOPED_TRACE("frame " + model.frames[f].name);
      const Eigen::Vector3d expected = framePlacement(model, data, f).translation;
      EXPECT_LT((framePosition<double>(model, x.q, f) - expected).norm(), 1e-12 * (1.0 + expected.norm()));
    }
  }
}

// dtau/da is the mass matrix: CRBA against central differences of RNEA. RNEA is affine
// in a, so a unit step is exact up to rounding (a small one only adds cancellation).
TEST_P(Properties, MassMatrixIsDerivativeOfRneaInA) {
  Data<double> data(model);
  State x = randomState(8);
  Eigen::MatrixXd fd(model.nv, model.nv);
  const double h = 1.0;
  for (int k = 0; k < model.nv; ++k) {
    Eigen::VectorXd ap = x.a, am = x.a;
    ap[k] += h;
    am[k] -= h;
    Eigen::VectorXd plus = rnea(model, data, x.q, x.v, ap);  // a copy: rnea returns data.tau
    fd.col(k) = (plus - rnea(model, data, x.q, x.v, am)) / (2 * h);
  }
  EXPECT_TRUE(matricesAgree(crba(model, data, x.q), fd, 1e-10));
}

TEST_P(Properties, CentreOfMassIsTheMassWeightedMeanOfBodies) {
  Data<double> data(model);
  State x = randomState(2);
  Eigen::Vector3d com = centerOfMass(model, data, x.q);
  // Independently: from every frame of a link that carries mass, through the URDF
  // masses is not possible after merging, so use the composite bodies' own frames.
  double mass = 0;
  Eigen::Vector3d weighted = Eigen::Vector3d::Zero();
  for (int j = 0; j < model.njoints(); ++j) {
    mass += model.bodies[j].mass;
    weighted += model.bodies[j].mass * data.oMi[j].act(model.bodies[j].lever);
  }
  EXPECT_NEAR(data.mass, mass, 1e-12 * mass);
  EXPECT_TRUE(matricesAgree(com, weighted / mass, 1e-12));
  // Physics: with a floating base, the linear-linear block of M is m 1 and the
  // linear-angular block is -m skew(c), c the centre of mass seen from the base.
  if (model.root != RootJoint::FreeFlyer) return;
  Eigen::MatrixXd M = crba(model, data, x.q);
  Eigen::Vector3d c_base = data.oMi[0].actInv(com);
  EXPECT_TRUE(matricesAgree(M.topLeftCorner<3, 3>(), mass * Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_TRUE(matricesAgree(M.block<3, 3>(0, 3), -mass * skew<double>(c_base), 1e-10));
}

// The algorithms are templates on the scalar: long double runs the same code and
// agrees with double.
TEST_P(Properties, AnotherScalarTypeRunsTheSameCode) {
  Data<double> data(model);
  Data<long double> data_ld(model);
  State x = randomState(1);
  using VecLD = VecX<long double>;
  VecLD q = x.q.cast<long double>(), v = x.v.cast<long double>(), a = x.a.cast<long double>();
  EXPECT_TRUE(matricesAgree(rnea(model, data_ld, q, v, a).cast<double>(), rnea(model, data, x.q, x.v, x.a), 1e-12));
  EXPECT_TRUE(matricesAgree(crba(model, data_ld, q).cast<double>(), crba(model, data, x.q), 1e-12));
  VecLD tau = rnea(model, data_ld, q, v, a);
  EXPECT_TRUE(matricesAgree(aba(model, data_ld, q, v, tau).cast<double>(), x.a, 1e-12));
  EXPECT_TRUE(matricesAgree(jointTorqueRegressor(model, data_ld, q, v, a).cast<double>(),
                            jointTorqueRegressor(model, data, x.q, x.v, x.a), 1e-12));
}

INSTANTIATE_TEST_SUITE_P(GeneratedRobots, Properties, ::testing::ValuesIn(cases()),
                         [](const auto& info) { return info.param.label; });

}  // namespace
}  // namespace robodiff
