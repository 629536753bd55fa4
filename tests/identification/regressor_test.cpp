// The stacked regressor against RNEA (an independent algorithm): W pi = tau for the model's
// parameters at every sample, on the generated function (interpreter); and the base
// parameters: W pi = W_base (B pi) for any pi, on states the decomposition never saw, with
// fewer base parameters than standard ones (the base link's parameters have no effect).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "identification_fixture.hpp"
#include "robodiff/batch/base_parameters.hpp"
#include "robodiff/batch/regressor_stack.hpp"
#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/regressor.hpp"
#include "robodiff/dynamics/rnea.hpp"

namespace robodiff::testing {
namespace {

batch::BatchFunction interpretedRegressor(const Robot& robot) {
  batch::BatchFunctionOptions options;
  options.backend = batch::Backend::Interpreted;
  options.threads = 2;
  return batch::openRegressor(robot.model, robot.urdf, false, options);
}

TEST(RegressorStack, TimesTheParametersEqualsRneaOfThePerturbedTruth) {
  const Robot robot = arm7();
  const Model truth = batch::perturbInertias(robot.model, 0.3, 11);
  // Noise-free samples of the truth; the regressor depends on kinematics only.
  const batch::MeasuredSamples s = batch::syntheticSamples(truth, syntheticOptions(40, 0.0));
  const batch::RegressorStack stack = batch::stackRegressor(interpretedRegressor(robot), robot.model, s);
  ASSERT_EQ(stack.W.rows(), 40 * 7);
  ASSERT_EQ(stack.W.cols(), 70);
  const Eigen::VectorXd pi = batch::modelParameters(truth);
  const Eigen::VectorXd predicted = stack.W * pi;
  Data<double> data(truth);
  for (Eigen::Index k = 0; k < 40; ++k) {
    const Eigen::VectorXd tau = rnea(truth, data, s.q.col(k), s.v.col(k), s.a.col(k));
    for (int i = 0; i < 7; ++i) {
      EXPECT_NEAR(predicted[k * 7 + i], tau[i], 1e-10 * (1 + std::abs(tau[i]))) << "sample " << k << " joint " << i;
      EXPECT_EQ(stack.tau[k * 7 + i], s.tau(i, k));
    }
  }
}

TEST(RegressorStack, ASliceStacksOnlyItsSamples) {
  const Robot robot = arm7();
  const batch::MeasuredSamples s = batch::syntheticSamples(robot.model, syntheticOptions(30, 0.0));
  const batch::BatchFunction f = interpretedRegressor(robot);
  const batch::RegressorStack all = batch::stackRegressor(f, robot.model, s);
  const batch::RegressorStack tail = batch::stackRegressor(f, robot.model, s, 20, 30);
  EXPECT_EQ(tail.samples(), 10u);
  EXPECT_EQ(tail.W, all.W.bottomRows(70));
  EXPECT_EQ(tail.tau, all.tau.tail(70));
}

TEST(BaseParameters, ReproduceTheTorquesOfAnyParametersOnUnseenStates) {
  const Robot robot = arm7();
  const batch::BaseParameters base = batch::computeBaseParameters(robot.model);
  const batch::ParameterLayout layout = batch::parameterLayout(robot.model);
  // 7 revolute joints on a fixed base: fewer base than standard parameters, a clear gap at the rank cut.
  EXPECT_LT(base.size(), 70);
  EXPECT_GT(base.size(), 30);
  EXPECT_GT(base.smallest_kept, 1e-6);
  EXPECT_LT(base.largest_dropped, 1e-12);
  EXPECT_EQ(base.B.rows(), base.size());
  EXPECT_EQ(static_cast<int>(base.independent.size() + base.dependent.size()), 70);
  // The first body turns about a fixed axis: its mass and first moments have no effect.
  for (int i : {0, 1, 2, 3}) EXPECT_NE(std::find(base.no_effect.begin(), base.no_effect.end(), i), base.no_effect.end());

  std::mt19937_64 rng(99);
  std::normal_distribution<double> gauss;
  Eigen::VectorXd pi(70);
  for (int i = 0; i < 70; ++i) pi[i] = gauss(rng);  // any parameters, physical or not
  Data<double> data(robot.model);
  for (int k = 0; k < 20; ++k) {
    const Eigen::VectorXd q = randomConfiguration(robot.model, rng);
    Eigen::VectorXd v(7), a(7);
    for (int i = 0; i < 7; ++i) v[i] = 2 * gauss(rng), a[i] = 2 * gauss(rng);
    const Eigen::MatrixXd Y = jointTorqueRegressor(robot.model, data, q, v, a);
    const Eigen::VectorXd full = Y * pi, reduced = base.baseColumns(Y) * base.fromStandard(pi);
    EXPECT_LT((full - reduced).norm(), 1e-9 * (1 + full.norm())) << "state " << k;
  }
  // Each base parameter reads as its leading parameter plus its combination.
  for (int k = 0; k < base.size(); ++k) EXPECT_EQ(base.describe(k, layout).rfind(base.name(k, layout), 0), 0u);
}

// Rounding must not choose the base: the same regressor with every entry moved by a few
// ulps (what another compiler flag or CPU does) gives the same parameters and
// combinations. arm7 has exactly tied columns, which pivoting alone broke by noise.
TEST(BaseParameters, RoundingNoiseDoesNotChangeTheChoice) {
  const Robot robot = arm7();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::MatrixXd W(40 * 7, 70);
  Data<double> data(robot.model);
  for (int k = 0; k < 40; ++k) {
    const Eigen::VectorXd q = randomConfiguration(robot.model, rng);
    Eigen::VectorXd v(7), a(7);
    for (int i = 0; i < 7; ++i) v[i] = unit(rng), a[i] = unit(rng);
    W.middleRows(7 * k, 7) = jointTorqueRegressor(robot.model, data, q, v, a);
  }
  const batch::BaseParameters reference = batch::baseParametersOf(W, 1e-8);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::MatrixXd noisy = W.unaryExpr([&](double x) { return x * (1 + 4e-16 * unit(rng)); });
    const batch::BaseParameters base = batch::baseParametersOf(noisy, 1e-8);
    EXPECT_EQ(base.independent, reference.independent) << "trial " << trial;
    EXPECT_EQ(base.dependent, reference.dependent) << "trial " << trial;
    if (base.K.rows() == reference.K.rows() && base.K.cols() == reference.K.cols())
      EXPECT_LT((base.K - reference.K).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
  }
}

TEST(BaseParameters, CompletingKeepsTheBaseValuesAndStaysNearThePrior) {
  const Robot robot = arm7();
  const batch::BaseParameters base = batch::computeBaseParameters(robot.model);
  const Eigen::VectorXd prior = batch::modelParameters(robot.model);
  const Eigen::VectorXd scales = batch::parameterScales(prior);
  const Eigen::VectorXd truth = batch::modelParameters(batch::perturbInertias(robot.model, 0.3, 5));
  for (const Eigen::VectorXd& s : {Eigen::VectorXd(), scales}) {
    const Eigen::VectorXd completed = base.complete(base.fromStandard(truth), prior, s);
    EXPECT_LT((base.fromStandard(completed) - base.fromStandard(truth)).norm(),
              1e-12 * base.fromStandard(truth).norm());
    // The closest such vector to the prior in the scaled norm: no farther than the truth,
    // which has the same base parameters.
    const Eigen::VectorXd w = s.size() ? s.cwiseInverse().eval() : Eigen::VectorXd::Ones(70).eval();
    EXPECT_LE((completed - prior).cwiseProduct(w).norm(), (truth - prior).cwiseProduct(w).norm() * (1 + 1e-12));
    // Parameters with no effect keep the prior's values.
    for (int i : base.no_effect) EXPECT_EQ(completed[i], prior[i]);
  }
}

}  // namespace
}  // namespace robodiff::testing
