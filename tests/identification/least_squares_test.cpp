// Least squares against a known truth: samples of a perturbed arm7 (masses and inertias
// changed physically), torques from RNEA of the truth plus Gaussian noise. Noise-free data
// give the truth's base parameters to ~1e-8; with noise the errors stay within a few
// standard errors (the tolerance scales with the noise), the estimated noise and the
// held-out residual RMS are near the noise's sigma; weighted least squares sees each
// joint's own noise; data that excite nothing are refused.
#include <cmath>

#include <gtest/gtest.h>

#include "identification_fixture.hpp"
#include "robodiff/batch/identification_error.hpp"

namespace robodiff::testing {
namespace {

struct Fitted {
  batch::IdentificationProblem problem;
  batch::IdentificationResult result;
  Eigen::VectorXd truth_base;
};

Fitted identifyArm7(const batch::SyntheticOptions& data, double holdout, bool weighted) {
  const Robot robot = arm7();
  const Model truth = batch::perturbInertias(robot.model, 0.3, 3);
  const batch::MeasuredSamples samples = batch::syntheticSamples(truth, data);
  const batch::IdentificationOptions options = interpretedOptions(holdout, weighted);
  Fitted f{batch::prepareIdentification(robot.model, robot.urdf, robot.path.string(), false, samples, options), {}, {}};
  f.result = batch::identifyLeastSquares(f.problem, options);
  f.truth_base = f.problem.base.fromStandard(batch::modelParameters(truth));
  return f;
}

TEST(LeastSquares, NoiseFreeSamplesGiveTheTruthsBaseParameters) {
  const Fitted f = identifyArm7(syntheticOptions(300, 0.0), 0.2, false);
  EXPECT_EQ(f.problem.fit.samples(), 240u);
  EXPECT_EQ(f.problem.held_out.samples(), 60u);
  const Eigen::VectorXd error = f.result.base_values - f.truth_base;
  for (Eigen::Index k = 0; k < error.size(); ++k)
    EXPECT_LE(std::abs(error[k]), 1e-8 * std::max(std::abs(f.truth_base[k]), 1e-2))
        << f.problem.base.describe(static_cast<int>(k), f.problem.layout);
  EXPECT_LT(f.result.rms_fit.maxCoeff(), 1e-9);
  EXPECT_LT(f.result.rms_held_out.maxCoeff(), 1e-9);
  // The URDF's own parameters do not explain the truth's torques.
  EXPECT_GT(f.result.rms_prior_held_out.maxCoeff(), 1e-3);
  // The completed parameters reproduce the truth's torques on unseen samples.
  EXPECT_LT((f.problem.held_out.W * f.result.parameters - f.problem.held_out.tau).norm(), 1e-8);
}

TEST(LeastSquares, WithNoiseTheErrorsStayWithinAFewStandardErrors) {
  const double sigma = 0.05;  // N m
  const Fitted f = identifyArm7(syntheticOptions(1500, sigma), 0.2, false);
  const Eigen::VectorXd error = f.result.base_values - f.truth_base;
  double chi2 = 0;
  for (Eigen::Index k = 0; k < error.size(); ++k) {
    const double se = f.result.base_std_errors[k];
    ASSERT_GT(se, 0);
    EXPECT_LE(std::abs(error[k]), 5 * se) << f.problem.base.describe(static_cast<int>(k), f.problem.layout);
    chi2 += error[k] * error[k] / (se * se);
  }
  // The normalised squared error's mean is about 1 (r degrees of freedom).
  const double r = static_cast<double>(error.size());
  EXPECT_LT(chi2, r + 5 * std::sqrt(2 * r));
  // The estimated noise and the residuals on fit and held-out data are sigma.
  EXPECT_NEAR(f.result.sigma, sigma, 0.05 * sigma);
  for (int j = 0; j < 7; ++j) {
    EXPECT_NEAR(f.result.joint_sigma[j], sigma, 0.15 * sigma) << "joint " << j;
    EXPECT_NEAR(f.result.rms_fit[j], sigma, 0.15 * sigma) << "joint " << j;
    EXPECT_NEAR(f.result.rms_held_out[j], sigma, 0.25 * sigma) << "joint " << j;
  }
  // Standard errors scale with the noise: ten times the noise, ten times the errors.
  const Fitted louder = identifyArm7(syntheticOptions(1500, 10 * sigma), 0.2, false);
  for (Eigen::Index k = 0; k < error.size(); ++k)
    EXPECT_NEAR(louder.result.base_std_errors[k] / f.result.base_std_errors[k], 10.0, 1.5);
}

TEST(LeastSquares, WeightedLeastSquaresEstimatesEachJointsNoise) {
  batch::SyntheticOptions data = syntheticOptions(1500, 0.0, 21);
  data.joint_noise.resize(7);
  data.joint_noise << 0.2, 0.2, 0.1, 0.05, 0.02, 0.01, 0.01;
  const Fitted ols = identifyArm7(data, 0.0, false);
  const Fitted wls = identifyArm7(data, 0.0, true);
  EXPECT_EQ(wls.result.method, "wls");
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(wls.result.joint_sigma[j], data.joint_noise[j], 0.15 * data.joint_noise[j]);
  // The weighted residuals are about unit variance, the errors within a few standard errors.
  EXPECT_NEAR(wls.result.sigma, 1.0, 0.1);
  const Eigen::VectorXd error = wls.result.base_values - wls.truth_base;
  for (Eigen::Index k = 0; k < error.size(); ++k) EXPECT_LE(std::abs(error[k]), 5 * wls.result.base_std_errors[k]);
  // Weighting by each joint's noise makes the estimate more precise than OLS's.
  EXPECT_LT(wls.result.base_std_errors.sum(), ols.result.base_std_errors.sum());
}

TEST(LeastSquares, StandardErrorsOfSingleParametersOnlyWhereDefined) {
  const Fitted f = identifyArm7(syntheticOptions(600, 0.05), 0.0, false);
  int defined = 0;
  for (int i = 0; i < f.problem.base.standard_count; ++i) {
    const bool alone = f.problem.base.combinationFor(i).has_value();
    EXPECT_EQ(std::isfinite(f.result.parameter_std_errors[i]), alone) << f.problem.layout.names[i];
    defined += alone;
  }
  // The last body's first moments are identifiable on their own; the first body's mass is not.
  EXPECT_GT(defined, 0);
  EXPECT_TRUE(std::isnan(f.result.parameter_std_errors[0]));
}

TEST(LeastSquares, SamplesThatExciteNothingAreRefused) {
  const Robot robot = arm7();
  batch::MeasuredSamples samples = batch::syntheticSamples(robot.model, syntheticOptions(200, 0.0));
  for (Eigen::Index k = 0; k < 200; ++k) samples.q.col(k) = samples.q.col(0);  // one posture,
  samples.v.setZero();                                                           // at rest
  samples.a.setZero();
  const batch::IdentificationOptions options = interpretedOptions();
  const batch::IdentificationProblem problem =
      batch::prepareIdentification(robot.model, robot.urdf, "arm7.urdf", false, samples, options);
  try {
    batch::identifyLeastSquares(problem, options);
    FAIL() << "no error";
  } catch (const batch::IdentificationError& e) {
    EXPECT_NE(std::string(e.what()).find("do not excite the base parameters"), std::string::npos) << e.what();
  }
  // Too few samples are refused before anything is computed.
  EXPECT_THROW(batch::prepareIdentification(robot.model, robot.urdf, "arm7.urdf", false,
                                            batch::sliceSamples(samples, 0, 3), options),
               batch::IdentificationError);
}

}  // namespace
}  // namespace robodiff::testing

namespace robodiff::testing {
namespace {

// A floating base (free-flyer root, base wrench among the torques): the base's own
// parameters and the total mass become identifiable; noise-free data still give the truth.
TEST(LeastSquares, FloatingBaseNoiseFree) {
  const Robot fixed = arm7();
  const Model model = loadUrdfString(fixed.urdf, RootJoint::FreeFlyer, "arm7.urdf");
  const Model truth = batch::perturbInertias(model, 0.3, 9);
  batch::SyntheticOptions data = syntheticOptions(200, 0.0);
  data.excitation = batch::Excitation::Random;
  const batch::MeasuredSamples samples = batch::syntheticSamples(truth, data);
  const batch::IdentificationOptions options = interpretedOptions(0.1);
  const batch::IdentificationProblem problem =
      batch::prepareIdentification(model, fixed.urdf, "arm7.urdf", true, samples, options);
  EXPECT_EQ(problem.base.standard_count, 80);
  EXPECT_EQ(problem.layout.bodies[0].link, "base_link");
  const batch::IdentificationResult result = batch::identifyLeastSquares(problem, options);
  const Eigen::VectorXd truth_base = problem.base.fromStandard(batch::modelParameters(truth));
  EXPECT_LT((result.base_values - truth_base).norm(), 1e-8 * truth_base.norm());
  EXPECT_LT(result.rms_held_out.maxCoeff(), 1e-8);
  // The total mass is seen by the base's force: the completed masses add up to the truth's.
  double mass = 0, truth_mass = 0;
  for (int j = 0; j < 8; ++j) mass += result.parameters[10 * j], truth_mass += truth.bodies[j].mass;
  EXPECT_NEAR(mass, truth_mass, 1e-8 * truth_mass);
}

}  // namespace
}  // namespace robodiff::testing
