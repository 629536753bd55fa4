// The analytic RNEA derivatives (dynamics/rnea_derivatives.hpp) against Pinocchio's
// computeRNEADerivatives in ../shared/golden (1e-9), and against central differences of
// rnea on the project's own robots (prismatic joints, a free-flyer, a branched tree); the
// tau of the same sweep against Pinocchio's and against rnea (local frames).
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/dynamics/rnea_derivatives.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/robot_cases.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::matricesAgree;

class RneaDerivativesGolden : public ::testing::TestWithParam<std::string> {};

TEST_P(RneaDerivativesGolden, MatchPinocchio) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  Data<double> data(model);
  MatX<double> dq, dv, da;
  for (const auto& x : golden.samples) {
    computeRneaDerivatives(model, data, x.q, x.v, x.a, dq, dv, da);
    EXPECT_TRUE(matricesAgree(dq, x.dtau_dq, 1e-9));
    EXPECT_TRUE(matricesAgree(dv, x.dtau_dv, 1e-9));
    EXPECT_TRUE(matricesAgree(da, x.M, 1e-9));
    EXPECT_TRUE(matricesAgree(data.tau, x.tau, 1e-9));  // tau from the same (world-frame) sweep
  }
}

INSTANTIATE_TEST_SUITE_P(Pinocchio, RneaDerivativesGolden, ::testing::Values("panda", "ur5", "talos", "talos_ff"));

class RneaDerivativesFiniteDifferences : public ::testing::TestWithParam<testing::RobotCase> {};

TEST_P(RneaDerivativesFiniteDifferences, MatchCentralDifferences) {
  const Model model = GetParam().load();
  Data<double> data(model);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int s = 0; s < 3; ++s) {
    const Eigen::VectorXd q = randomConfiguration(model, rng);
    const Eigen::VectorXd v = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
    const Eigen::VectorXd a = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
    MatX<double> dq, dv, da;
    computeRneaDerivatives(model, data, q, v, a, dq, dv, da);
    const Eigen::VectorXd sweep_tau = data.tau;
    EXPECT_TRUE(matricesAgree(sweep_tau, rnea(model, data, q, v, a), 1e-12));  // the local-frame RNEA
    const double h = 1e-6;
    Eigen::MatrixXd fq(model.nv, model.nv), fv(model.nv, model.nv);
    // rnea returns data.tau: copy before the next call.
    auto tau = [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv) -> Eigen::VectorXd {
      return rnea(model, data, qq, vv, a);
    };
    for (int j = 0; j < model.nv; ++j) {
      const Eigen::VectorXd e = Eigen::VectorXd::Unit(model.nv, j) * h;
      fq.col(j) = (tau(integrate(model, q, e), v) - tau(integrate(model, q, -e), v)) / (2 * h);
      fv.col(j) = (tau(q, v + e) - tau(q, v - e)) / (2 * h);
    }
    EXPECT_TRUE(matricesAgree(dq, fq, 1e-5));
    EXPECT_TRUE(matricesAgree(dv, fv, 1e-5));
    EXPECT_TRUE(matricesAgree(da, crba(model, data, q), 1e-12));
  }
}

INSTANTIATE_TEST_SUITE_P(GeneratedRobots, RneaDerivativesFiniteDifferences,
                         ::testing::ValuesIn(testing::branchedAndPrismaticRobots()),
                         [](const auto& info) { return info.param.label; });

}  // namespace
}  // namespace robodiff
