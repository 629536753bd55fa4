// What ABA's derivatives are made of, from one world-frame sweep
// (dynamics/aba_derivatives.hpp): ddq against Pinocchio's ABA in ../shared/golden and the
// partials assembled into d ddq/d(q, v) against its computeABADerivatives (1e-9); on the
// project's own robots (a free-flyer, four legs on a trunk fixed to the world, prismatic
// joints), every term against the separate algorithms: aba, the RNEA partials at
// a = ddq, and M from crba, factorised.
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/aba_derivatives.hpp"
#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/robot_cases.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::matricesAgree;

class AbaDerivativeTermsGolden : public ::testing::TestWithParam<std::string> {};

TEST_P(AbaDerivativeTermsGolden, MatchPinocchio) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  Data<double> data(model);
  for (const auto& x : golden.samples) {
    const AbaDerivativeTerms<double> t = computeAbaDerivativeTerms(model, data, x.q, x.v, x.tau);
    EXPECT_TRUE(matricesAgree(t.ddq, x.ddq, 1e-9));
    const Eigen::MatrixXd Minv = inverseFromFactors(dofParents(model), t.mass_factors);
    EXPECT_TRUE(matricesAgree(Minv, x.M.inverse(), 1e-9));
    EXPECT_TRUE(matricesAgree(-Minv * t.dtau_dq, x.dddq_dq, 1e-9));
    EXPECT_TRUE(matricesAgree(-Minv * t.dtau_dv, x.dddq_dv, 1e-9));
  }
}

INSTANTIATE_TEST_SUITE_P(Pinocchio, AbaDerivativeTermsGolden, ::testing::Values("panda", "ur5", "talos", "talos_ff"));

class AbaDerivativeTermsAgainstSeparateAlgorithms : public ::testing::TestWithParam<testing::RobotCase> {};

TEST_P(AbaDerivativeTermsAgainstSeparateAlgorithms, AgreeWithAbaRneaPartialsAndCrba) {
  const Model model = GetParam().load();
  Data<double> data(model);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  const std::vector<int> lambda = dofParents(model);
  for (int s = 0; s < 3; ++s) {
    const Eigen::VectorXd q = randomConfiguration(model, rng);
    const Eigen::VectorXd v = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
    const Eigen::VectorXd tau = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return 10 * u(rng); });
    const AbaDerivativeTerms<double> t = computeAbaDerivativeTerms(model, data, q, v, tau);
    const Eigen::VectorXd ddq = aba(model, data, q, v, tau);
    EXPECT_TRUE(matricesAgree(t.ddq, ddq, 1e-10));
    MatX<double> dq, dv, da;
    computeRneaDerivatives(model, data, q, v, ddq, dq, dv, da);
    EXPECT_TRUE(matricesAgree(t.dtau_dq, dq, 1e-10));
    EXPECT_TRUE(matricesAgree(t.dtau_dv, dv, 1e-10));
    MatX<double> factors = crba(model, data, q);
    factorizeMassMatrix(lambda, factors);
    EXPECT_TRUE(matricesAgree(t.mass_factors.triangularView<Eigen::Lower>().toDenseMatrix(),
                              factors.triangularView<Eigen::Lower>().toDenseMatrix(), 1e-10));
    // The factors solve: M^-1 M = I, by the product over common ancestors and by a solve.
    const MatX<double> M = crba(model, data, q);
    EXPECT_TRUE(matricesAgree(inverseFromFactors(lambda, t.mass_factors) * M,
                              Eigen::MatrixXd::Identity(model.nv, model.nv), 1e-9));
    EXPECT_TRUE(matricesAgree(solveWithFactors(lambda, t.mass_factors, VecX<double>(M * v)), v, 1e-9));
  }
}

INSTANTIATE_TEST_SUITE_P(GeneratedRobots, AbaDerivativeTermsAgainstSeparateAlgorithms,
                         ::testing::ValuesIn(testing::branchedAndPrismaticRobots()),
                         [](const auto& info) { return info.param.label; });

}  // namespace
}  // namespace robodiff
