// Physically consistent identification (identifyPhysical) against independent references:
// synthetic samples of a perturbed arm7 (the truth, physically valid), every identified
// body checked with checkBodyValidity and, independently, through the eigenvalues of its
// 4 x 4 pseudo-inertia built here from the centre of mass and the inertia about it; held-out torques against the
// noise level and against least squares on the same problem. Poor data (a few slow
// samples, heavy noise) make least squares return an invalid body, and the physical fit
// still returns valid ones that predict no worse.
#include <cmath>
#include <cstdio>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "identification_fixture.hpp"
#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/physical_identification.hpp"
#include "robodiff/batch/physical_validity.hpp"
#include "robodiff/batch/urdf_inertials.hpp"

namespace robodiff::testing {
namespace {

// The pseudo-inertia J = integral of [r; 1][r; 1]^T dm of one body's 10 parameters, built
// here from the centre of mass c and the inertia about it I_c: the second moment about c is
// 0.5 tr(I_c) 1 - I_c, and moving it to the origin adds m [c; 1][c; 1]^T. Positive definite
// exactly when the body is physically valid (for m <= 0, J's last diagonal entry is m).
Eigen::Matrix4d pseudoInertia(const Eigen::VectorXd& p) {
  const batch::BodyInertial b = batch::inertialFromParameters(p);
  Eigen::Vector4d c1;
  c1 << b.com, 1;
  Eigen::Matrix4d j = b.mass * c1 * c1.transpose();
  j.topLeftCorner<3, 3>() += 0.5 * b.inertia.trace() * Eigen::Matrix3d::Identity() - b.inertia;
  return j;
}

double smallestEigenvalue(const Eigen::Matrix4d& j) {
  // Dynamic size: GCC 12 warns (spuriously) inside Eigen's unrolled code for a fixed 4 x 4.
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(j), Eigen::EigenvaluesOnly).eigenvalues()[0];
}

// Every body valid by both checks.
void expectAllValid(const Eigen::VectorXd& pi) {
  for (Eigen::Index b = 0; b < pi.size() / 10; ++b) {
    const Eigen::VectorXd body = pi.segment(10 * b, 10);
    const batch::BodyValidity v = batch::checkBodyValidity(body);
    EXPECT_TRUE(v.valid) << "body " << b << ": " << v.message;
    EXPECT_GT(smallestEigenvalue(pseudoInertia(body)), 0) << "body " << b;
  }
}

double rms(const batch::RegressorStack& stack, const Eigen::VectorXd& pi) {
  return std::sqrt((stack.W * pi - stack.tau).squaredNorm() / static_cast<double>(stack.tau.size()));
}

struct Arm7Truth {
  Robot robot = arm7();
  Model truth = batch::perturbInertias(robot.model, 0.3, 3);
};

// Poor fitted data, rich held-out data (poorThenRichSamples): the 300 rich samples held out.
batch::IdentificationProblem poorProblem(const Arm7Truth& w, double sigma, std::size_t poor) {
  const batch::MeasuredSamples samples = poorThenRichSamples(w.truth, sigma, poor, 300);
  const double holdout = 300.0 / static_cast<double>(samples.size());
  return batch::prepareIdentification(w.robot.model, w.robot.urdf, w.robot.path.string(), false, samples,
                                      interpretedOptions(holdout));
}

TEST(PhysicalIdentification, PoorDataGiveValidBodiesWhereLeastSquaresDoesNot) {
  const Arm7Truth w;
  const double sigma = 0.5;
  const batch::IdentificationProblem problem = poorProblem(w, sigma, 30);
  ASSERT_EQ(problem.held_out.samples(), 300u);

  const batch::IdentificationResult ls = batch::identifyLeastSquares(problem, interpretedOptions());
  ASSERT_FALSE(batch::allValid(batch::checkValidity(ls.parameters)))
      << "the data are not poor enough to make the point";
  bool flagged = false, indefinite = false;
  for (const batch::BodyResult& b : ls.bodies) flagged |= !b.validity.valid;
  EXPECT_TRUE(flagged) << "the least-squares report flags an invalid body";
  for (Eigen::Index b = 0; b < 7; ++b)  // and the independent check sees it
    indefinite |= smallestEigenvalue(pseudoInertia(ls.parameters.segment(10 * b, 10))) <= 0;
  EXPECT_TRUE(indefinite);

  const batch::IdentificationResult physical = batch::identifyPhysical(problem, interpretedOptions());
  EXPECT_EQ(physical.method, "physical");
  ASSERT_TRUE(physical.solver.has_value());
  EXPECT_TRUE(physical.solver->success) << physical.solver->status;
  EXPECT_EQ(physical.solver->weighting, "ols");
  EXPECT_GT(physical.solver->iterations, 0);
  expectAllValid(physical.parameters);
  for (const batch::BodyResult& b : physical.bodies) EXPECT_TRUE(b.validity.valid) << b.validity.message;

  // Held-out torques, computed here from the stacked regressor: no worse than least squares.
  const double physical_rms = rms(problem.held_out, physical.parameters), ls_rms = rms(problem.held_out, ls.parameters);
  EXPECT_LE(physical_rms, ls_rms) << "physical " << physical_rms << ", least squares " << ls_rms;
  std::printf("poor data: held-out RMS least squares %.4g, physical %.4g, the URDF's %.4g (noise %.3g N m)\n", ls_rms,
              physical_rms, rms(problem.held_out, problem.prior), sigma);
  EXPECT_NEAR(physical.rms_held_out.norm() / std::sqrt(7.0), physical_rms, 1e-9 * physical_rms);
  // The URDF's parameters are the fallback: the physical fit is not worse than them either.
  EXPECT_LE(physical_rms, rms(problem.held_out, problem.prior) * 1.05);

  // Weighted by each joint's noise from an OLS pass: still valid.
  batch::IdentificationOptions weighted = interpretedOptions();
  weighted.weighted = true;
  const batch::IdentificationResult physical_wls = batch::identifyPhysical(problem, weighted);
  EXPECT_EQ(physical_wls.solver->weighting, "per-joint noise");
  EXPECT_TRUE(std::isfinite(physical_wls.joint_sigma[0]));
  expectAllValid(physical_wls.parameters);
}

TEST(PhysicalIdentification, RichDataPredictHeldOutTorquesAtTheNoiseLevel) {
  const Arm7Truth w;
  const double sigma = 0.05;
  const batch::MeasuredSamples samples = batch::syntheticSamples(w.truth, syntheticOptions(1000, sigma, 41));
  const batch::IdentificationOptions options = interpretedOptions(0.25);
  const batch::IdentificationProblem problem =
      batch::prepareIdentification(w.robot.model, w.robot.urdf, w.robot.path.string(), false, samples, options);
  const batch::IdentificationResult result = batch::identifyPhysical(problem, options);
  ASSERT_TRUE(result.solver.has_value());
  EXPECT_TRUE(result.solver->success) << result.solver->status;
  expectAllValid(result.parameters);
  EXPECT_EQ(result.rms_held_out.size(), 7);
  for (int j = 0; j < 7; ++j) EXPECT_LT(result.rms_held_out[j], 1.3 * sigma) << "joint " << j;
  EXPECT_LT(rms(problem.held_out, result.parameters), 1.3 * sigma);
  const batch::IdentificationResult ls = batch::identifyLeastSquares(problem, options);
  std::printf("rich data: held-out RMS least squares %.4g, physical %.4g (noise %.3g N m)\n",
              rms(problem.held_out, ls.parameters), rms(problem.held_out, result.parameters), sigma);
  // The URDF's own parameters explain the truth's torques far worse.
  EXPECT_GT(rms(problem.held_out, problem.prior), 3 * sigma);
  // The times of the problem, then the fit's phases.
  bool ipopt_phase = false;
  for (const batch::PhaseTime& t : result.times) ipopt_phase |= t.phase == "physically consistent fit (Ipopt)";
  EXPECT_TRUE(ipopt_phase);
}

TEST(PhysicalIdentification, NormalEquationsWeighEachJointsRows) {
  // Against the normal equations formed here from the whole stack.
  const Arm7Truth w;
  const batch::MeasuredSamples samples = batch::syntheticSamples(w.truth, syntheticOptions(2100, 0.01, 51));
  const batch::IdentificationProblem problem = batch::prepareIdentification(
      w.robot.model, w.robot.urdf, w.robot.path.string(), false, samples, interpretedOptions());
  Eigen::VectorXd joint(7);
  joint << 1, 2, 3, 4, 5, 6, 7;
  const batch::NormalEquations got = batch::stackNormalEquations(problem.fit, joint);
  const Eigen::MatrixXd W = problem.fit.W;
  Eigen::VectorXd d(W.rows());
  for (Eigen::Index i = 0; i < d.size(); ++i) d[i] = joint[i % 7];
  const Eigen::MatrixXd gram = W.transpose() * d.asDiagonal() * W;
  EXPECT_LT((got.gram - gram).norm(), 1e-10 * gram.norm());
  EXPECT_LT((got.moment - W.transpose() * d.asDiagonal() * problem.fit.tau).norm(), 1e-10 * got.moment.norm());
  EXPECT_NEAR(got.energy, problem.fit.tau.dot(d.asDiagonal() * problem.fit.tau), 1e-10 * got.energy);
  EXPECT_EQ(got.rows, W.rows());
  EXPECT_THROW(batch::stackNormalEquations(problem.fit, Eigen::VectorXd::Ones(3)), batch::IdentificationError);
}

}  // namespace
}  // namespace robodiff::testing
