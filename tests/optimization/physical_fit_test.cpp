// The physically consistent inertial-parameter fit, against independent references: the
// log-Cholesky map's round trip and the eigenvalues of the pseudo-inertia (every theta is a
// valid body), central finite differences of the double-precision map (the generated
// Jacobian and weighted Hessian) and of the program's objective (its gradient and exact
// Hessian), the residual computed from the regressor itself, and synthetic identification
// on the project's arm7 with known true parameters (rich and poor data, the latter against
// ordinary least squares), cancellation.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include "robodiff/batch/physical_fit.hpp"
#include "robodiff/batch/physical_log_cholesky.hpp"
#include "robodiff/batch/physical_log_cholesky_derivatives.hpp"
#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/regressor.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using batch::BodyVector;
using Vec10 = Eigen::Matrix<double, 10, 1>;
using Mat10 = Eigen::Matrix<double, 10, 10>;

// theta with spreads per kind of coordinate: alpha and d (logs), s (m), t (m).
Vec10 randomTheta(std::mt19937& rng, double log_spread, double length_spread) {
  std::normal_distribution<double> n(0, 1);
  Vec10 theta;
  for (int i = 0; i < 4; ++i) theta[i] = log_spread * n(rng);
  for (int i = 4; i < 10; ++i) theta[i] = length_spread * n(rng);
  return theta;
}

// The pseudo-inertia written out here from its definition (Wensing et al. 2017), not the
// library's: [[0.5 tr(I) 1 - I, m c], [m c^T, m]].
Eigen::Matrix4d pseudoInertiaOf(const Vec10& pi) {
  Eigen::Matrix3d inertia;
  inertia << pi[4], pi[5], pi[7], pi[5], pi[6], pi[8], pi[7], pi[8], pi[9];
  Eigen::Matrix4d j = Eigen::Matrix4d::Zero();
  j.topLeftCorner<3, 3>() = 0.5 * inertia.trace() * Eigen::Matrix3d::Identity() - inertia;
  j.block<3, 1>(0, 3) = pi.segment<3>(1);
  j.block<1, 3>(3, 0) = pi.segment<3>(1).transpose();
  j(3, 3) = pi[0];
  return j;
}

// Dynamic size: GCC 12 warns (spuriously) inside Eigen's unrolled AVX-512 code for a fixed 4 x 4.
double minEigenvalue(const Eigen::MatrixXd& j) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(j, Eigen::EigenvaluesOnly).eigenvalues()[0];
}

TEST(PhysicalLogCholesky, RoundTripThetaToParametersToTheta) {
  std::mt19937 rng(1);
  for (int k = 0; k < 200; ++k) {
    const Vec10 theta = randomTheta(rng, 1.0, 0.3);
    const Vec10 pi = batch::parametersFromLogCholesky<double>(theta);
    const Vec10 back = batch::logCholeskyFromParameters(pi);
    EXPECT_LT((back - theta).cwiseAbs().maxCoeff(), 1e-9) << "theta " << theta.transpose();
  }
}

TEST(PhysicalLogCholesky, UrdfBodiesRoundTrip) {
  const Model model = loadUrdfFile((sourceDir() / "examples/robots/arm7.urdf").string());
  for (const Inertia<double>& body : model.bodies) {
    const Vec10 pi = body.parameters();
    const Vec10 again = batch::parametersFromLogCholesky<double>(batch::logCholeskyFromParameters(pi));
    EXPECT_LT((again - pi).cwiseAbs().maxCoeff(), 1e-12 * (1 + pi.cwiseAbs().maxCoeff()));
  }
}

TEST(PhysicalLogCholesky, AnyThetaIsAValidBody) {
  std::mt19937 rng(2);
  for (int k = 0; k < 1000; ++k) {
    const Vec10 theta = randomTheta(rng, 1.0, 0.5);
    const Vec10 pi = batch::parametersFromLogCholesky<double>(theta);
    const batch::BodyValidity v = batch::checkBodyValidity(pi);
    EXPECT_TRUE(v.valid) << v.message;
    EXPECT_GT(v.mass, 0);
    EXPECT_GT(v.principal_moments.minCoeff(), 0);
    EXPECT_GE(v.triangle_margin, 0);
    const Eigen::MatrixXd j = pseudoInertiaOf(pi);
    EXPECT_GT(minEigenvalue(j), 0) << "theta " << theta.transpose();
    EXPECT_NEAR(v.pseudo_inertia_min_eigenvalue, minEigenvalue(j), 1e-12 * j.norm());
  }
}

// The check agrees with the pseudo-inertia criterion (J positive semidefinite and m > 0
// is physical consistency) on random bodies on both sides of the boundary.
TEST(PhysicalValidity, AgreesWithPseudoInertiaEigenvalues) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  int valid = 0, invalid = 0;
  for (int k = 0; k < 2000; ++k) {
    Vec10 pi = batch::parametersFromLogCholesky<double>(randomTheta(rng, 0.5, 0.2));
    for (int i = 0; i < 10; ++i) pi[i] += 0.3 * n(rng) * std::abs(pi[i]);
    const Eigen::MatrixXd j = pseudoInertiaOf(pi);
    const double min_eig = minEigenvalue(j);
    if (std::abs(min_eig) < 1e-9 * j.norm()) continue;  // too close to call
    const batch::BodyValidity v = batch::checkBodyValidity(pi);
    EXPECT_EQ(v.valid, min_eig > 0 && pi[0] > 0) << pi.transpose() << "\n" << v.message;
    (v.valid ? valid : invalid)++;
    if (!v.valid) {
      EXPECT_FALSE(v.message.empty());
    }
  }
  EXPECT_GT(valid, 100);
  EXPECT_GT(invalid, 100);
}

TEST(PhysicalValidity, NamesWhatFails) {
  // 2 kg centred at (0.1, 0, 0), principal moments violating the triangle inequality.
  Vec10 pi;
  const double m = 2, cx = 0.1;
  const Eigen::Vector3d moments(0.01, 0.01, 0.05);  // 0.05 > 0.01 + 0.01
  pi << m, m * cx, 0, 0, moments[0], 0, moments[1] + m * cx * cx, 0, 0, moments[2] + m * cx * cx;
  batch::BodyValidity v = batch::checkBodyValidity(pi);
  EXPECT_FALSE(v.valid);
  EXPECT_NEAR(v.triangle_margin, -0.03, 1e-12);
  EXPECT_NE(v.message.find("triangle"), std::string::npos) << v.message;
  pi[0] = -1;
  v = batch::checkBodyValidity(pi);
  EXPECT_NE(v.message.find("mass"), std::string::npos) << v.message;
  const std::vector<batch::BodyValidity> all = batch::checkValidity(Eigen::VectorXd::Zero(20));
  EXPECT_FALSE(batch::allValid(all));
  EXPECT_NE(batch::describeInvalid(all).find("body 1"), std::string::npos);
}

TEST(PhysicalLogCholesky, ProjectsAnInvalidPriorIntoTheValidSet) {
  std::mt19937 rng(4);
  bool changed = true;
  const Vec10 valid = batch::parametersFromLogCholesky<double>(randomTheta(rng, 0.5, 0.1));
  EXPECT_EQ(batch::projectToStrictlyValid(valid, 1e-3, &changed), valid);
  EXPECT_FALSE(changed);
  // A massless link, and a flat body (zero thickness: triangle inequality with equality).
  Vec10 flat;
  flat << 1, 0, 0, 0, 0.01, 0, 0.01, 0, 0, 0.02;
  for (const Vec10& pi : {Vec10(Vec10::Zero()), flat}) {
    const Vec10 p = batch::projectToStrictlyValid(pi, 1e-3, &changed);
    EXPECT_TRUE(changed);
    EXPECT_GT(minEigenvalue(pseudoInertiaOf(p)), 0) << p.transpose();
    EXPECT_TRUE(batch::checkBodyValidity(p).valid);
    EXPECT_LT((p - pi).norm(), 1e-3 + 1e-5);  // only slightly moved
  }
}

// The generated Jacobian and weighted Hessian against central differences of the
// double-precision map.
TEST(PhysicalLogCholeskyDerivatives, MatchFiniteDifferences) {
  const batch::LogCholeskyDerivatives derivatives;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  auto map = [](const Vec10& t) { return batch::parametersFromLogCholesky<double>(t); };
  for (int k = 0; k < 20; ++k) {
    const Vec10 theta = randomTheta(rng, 0.5, 0.3);
    Vec10 w;
    for (int i = 0; i < 10; ++i) w[i] = n(rng);
    Vec10 pi;
    Mat10 jacobian;
    derivatives.valueAndJacobian(theta, pi, jacobian);
    EXPECT_LT((pi - map(theta)).cwiseAbs().maxCoeff(), 1e-13 * (1 + map(theta).cwiseAbs().maxCoeff()));

    const double h = 1e-6;
    Mat10 fd;
    for (int j = 0; j < 10; ++j) {
      const Vec10 e = Vec10::Unit(j) * h;
      fd.col(j) = (map(theta + e) - map(theta - e)) / (2 * h);
    }
    EXPECT_LT((jacobian - fd).cwiseAbs().maxCoeff(), 1e-7 * (1 + fd.cwiseAbs().maxCoeff()));

    // sum_k w_k d^2 pi_k / d theta_i d theta_j: second central differences of w . pi.
    const Mat10 hessian = derivatives.weightedHessian(theta, w);
    const double g = 1e-4;
    auto f = [&](const Vec10& t) { return w.dot(map(t)); };
    Mat10 fd2;
    for (int i = 0; i < 10; ++i)
      for (int j = 0; j < 10; ++j) {
        const Vec10 ei = Vec10::Unit(i) * g, ej = Vec10::Unit(j) * g;
        fd2(i, j) = (f(theta + ei + ej) - f(theta + ei - ej) - f(theta - ei + ej) + f(theta - ei - ej)) / (4 * g * g);
      }
    EXPECT_LT((hessian - fd2).cwiseAbs().maxCoeff(), 1e-5 * (1 + fd2.cwiseAbs().maxCoeff()));
    EXPECT_LT((hessian - hessian.transpose()).cwiseAbs().maxCoeff(), 1e-14 * (1 + hessian.cwiseAbs().maxCoeff()));
  }
}

// A small random problem: 3 bodies, random weighted rows, a prior with a massless body.
TEST(PhysicalFitProgram, DerivativesMatchFiniteDifferencesOfTheObjective) {
  std::mt19937 rng(6);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> u(0.2, 2.0);
  const int bodies = 3, rows = 50;
  Eigen::MatrixXd w(rows, 10 * bodies);
  Eigen::VectorXd tau(rows), weights(rows);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < w.cols(); ++c) w(r, c) = n(rng);
    tau[r] = 3 * n(rng);
    weights[r] = u(rng);
  }
  Eigen::VectorXd prior(10 * bodies);
  for (int b = 0; b < bodies; ++b)
    prior.segment<10>(10 * b) = batch::parametersFromLogCholesky<double>(randomTheta(rng, 0.3, 0.1));
  prior.segment<10>(10).setZero();
  const double lambda = 0.05;
  batch::PhysicalFitProgram program(batch::normalEquations(w, tau, weights), prior, lambda);
  EXPECT_EQ(program.projectedBodies(), std::vector<int>{1});
  ASSERT_EQ(program.variableCount(), 30);

  for (int k = 0; k < 3; ++k) {
    Eigen::VectorXd x(30);
    for (int b = 0; b < bodies; ++b) x.segment<10>(10 * b) = randomTheta(rng, 0.3, 0.2);
    auto f = [&](const Eigen::VectorXd& at) { return program.objective({at.data(), 30}); };
    auto grad = [&](const Eigen::VectorXd& at) {
      Eigen::VectorXd g(30);
      program.gradient({at.data(), 30}, {g.data(), 30});
      return g;
    };

    // The data term from the regressor itself (not the normal equations).
    const Eigen::VectorXd pi = program.parameters(x);
    const double direct = (weights.array() * (w * pi - tau).array().square()).sum();
    EXPECT_NEAR(program.dataResidual(pi), direct, 1e-10 * direct);
    EXPECT_NEAR(f(x) * program.dataEnergy(), direct + program.regularization(pi), 1e-10 * direct);
    EXPECT_NEAR(program.dataEnergy(), (weights.array() * tau.array().square()).sum(), 1e-9);

    const double h = 1e-6;
    Eigen::VectorXd fd(30);
    for (int i = 0; i < 30; ++i) {
      const Eigen::VectorXd e = Eigen::VectorXd::Unit(30, i) * h;
      fd[i] = (f(x + e) - f(x - e)) / (2 * h);
    }
    const Eigen::VectorXd g = grad(x);
    EXPECT_LT((g - fd).cwiseAbs().maxCoeff(), 1e-6 * (1 + fd.cwiseAbs().maxCoeff()));

    // Exact Hessian (lower triangle, scaled by the objective factor) against differences of the gradient.
    const batch::SparsityEntries pattern = program.hessianPattern();
    std::vector<double> values(pattern.size());
    const double sigma = 0.7;
    program.hessian({x.data(), 30}, sigma, {}, values);
    Eigen::MatrixXd hess = Eigen::MatrixXd::Zero(30, 30);
    for (std::size_t e = 0; e < pattern.size(); ++e) {
      ASSERT_GE(pattern[e].first, pattern[e].second);
      hess(pattern[e].first, pattern[e].second) = hess(pattern[e].second, pattern[e].first) = values[e] / sigma;
    }
    Eigen::MatrixXd fd2(30, 30);
    for (int i = 0; i < 30; ++i) {
      const Eigen::VectorXd e = Eigen::VectorXd::Unit(30, i) * h;
      fd2.col(i) = (grad(x + e) - grad(x - e)) / (2 * h);
    }
    EXPECT_LT((hess - fd2).cwiseAbs().maxCoeff(), 1e-6 * (1 + fd2.cwiseAbs().maxCoeff()));
  }
}

// Synthetic identification on the project's arm7: true parameters are the URDF's moved in
// log-Cholesky coordinates (so physically valid), torques = W pi_true + Gaussian noise.
class PhysicalFitArm7 : public ::testing::Test {
 protected:
  Model model = loadUrdfFile((sourceDir() / "examples/robots/arm7.urdf").string());
  Eigen::VectorXd prior = inertialParameters(model);
  Eigen::VectorXd truth = perturbed(prior, 7);

  Eigen::VectorXd perturbed(const Eigen::VectorXd& pi, unsigned seed) const {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0, 1);
    Eigen::VectorXd out(pi.size());
    for (Eigen::Index b = 0; b < pi.size() / 10; ++b) {
      Vec10 theta = batch::logCholeskyFromParameters(pi.segment<10>(10 * b));
      for (int i = 0; i < 4; ++i) theta[i] += 0.15 * n(rng);     // mass and shape, ~15 %
      for (int i = 4; i < 10; ++i) theta[i] += 0.02 * n(rng);    // centre of mass and skew, ~2 cm
      out.segment<10>(10 * b) = batch::parametersFromLogCholesky<double>(theta);
    }
    return out;
  }

  // Stacked regressor of `samples` states: q around `centre` within +-q_spread (and the
  // limits), velocities and accelerations uniform within +-v_spread, +-a_spread.
  Eigen::MatrixXd regressor(int samples, unsigned seed, const Eigen::VectorXd& centre, double q_spread,
                            double v_spread, double a_spread) const {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    Data<double> data(model);
    const Eigen::VectorXd lo = model.lowerPositionLimit(), hi = model.upperPositionLimit();
    Eigen::MatrixXd w(samples * model.nv, 10 * model.njoints());
    for (int s = 0; s < samples; ++s) {
      Eigen::VectorXd q(model.nq), v(model.nv), a(model.nv);
      for (int i = 0; i < model.nq; ++i) q[i] = std::clamp(centre[i] + q_spread * u(rng), lo[i], hi[i]);
      for (int i = 0; i < model.nv; ++i) v[i] = v_spread * u(rng), a[i] = a_spread * u(rng);
      w.middleRows(s * model.nv, model.nv) = jointTorqueRegressor(model, data, q, v, a);
    }
    return w;
  }

  Eigen::VectorXd noisy(const Eigen::VectorXd& clean, double sigma, unsigned seed) const {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0, sigma);
    Eigen::VectorXd out = clean;
    for (Eigen::Index i = 0; i < out.size(); ++i) out[i] += n(rng);
    return out;
  }

  Eigen::VectorXd middle() const { return 0.5 * (model.lowerPositionLimit() + model.upperPositionLimit()); }

  static double rms(const Eigen::VectorXd& r) { return std::sqrt(r.squaredNorm() / static_cast<double>(r.size())); }
};

TEST_F(PhysicalFitArm7, RichDataPredictsHeldOutTorquesAtTheNoiseLevel) {
  ASSERT_EQ(prior.size(), 70);
  const double sigma = 0.3;  // N m
  const Eigen::MatrixXd w = regressor(1000, 11, middle(), 2.0, 2.0, 5.0);
  const Eigen::VectorXd tau = noisy(w * truth, sigma, 12);
  const batch::PhysicalFitResult fit = fitPhysicalParameters(batch::normalEquations(w, tau), prior);
  EXPECT_TRUE(fit.success) << fit.status;
  EXPECT_TRUE(batch::allValid(fit.validity)) << batch::describeInvalid(fit.validity);
  for (Eigen::Index b = 0; b < 7; ++b)
    EXPECT_GT(minEigenvalue(pseudoInertiaOf(fit.parameters.segment<10>(10 * b))), 0);

  const Eigen::MatrixXd w_test = regressor(300, 13, middle(), 2.0, 2.0, 5.0);
  const Eigen::VectorXd tau_test = noisy(w_test * truth, sigma, 14);
  const double held_out = rms(w_test * fit.parameters - tau_test);
  EXPECT_LT(held_out, 1.5 * sigma) << "held-out RMS " << held_out << ", prior's " << rms(w_test * prior - tau_test);
  EXPECT_NEAR(fit.residual_rms, rms(w * fit.parameters - tau), 1e-9);
  EXPECT_LT(fit.residual_rms, 1.2 * sigma);
}

TEST_F(PhysicalFitArm7, PoorDataStillGiveValidBodiesAndPredictNoWorseThanLeastSquares) {
  // A few slow samples near one pose, heavy noise.
  const double sigma = 1.0;
  const Eigen::MatrixXd w = regressor(30, 21, middle(), 0.3, 0.3, 0.5);
  const Eigen::VectorXd tau = noisy(w * truth, sigma, 22);

  // Ordinary least squares, the minimum-norm step from the prior (the parameters the data
  // cannot see stay at the URDF's): it makes at least one body physically invalid.
  const Eigen::VectorXd ols = prior + w.completeOrthogonalDecomposition().solve(tau - w * prior);
  const std::vector<batch::BodyValidity> ols_validity = batch::checkValidity(ols);
  ASSERT_FALSE(batch::allValid(ols_validity)) << "the data are not poor enough to make a point";

  const batch::PhysicalFitResult fit = fitPhysicalParameters(batch::normalEquations(w, tau), prior);
  EXPECT_TRUE(fit.success) << fit.status;
  EXPECT_TRUE(batch::allValid(fit.validity)) << batch::describeInvalid(fit.validity);
  for (Eigen::Index b = 0; b < 7; ++b)
    EXPECT_GT(minEigenvalue(pseudoInertiaOf(fit.parameters.segment<10>(10 * b))), 0);

  // Held out: rich motions over the workspace.
  const Eigen::MatrixXd w_test = regressor(300, 23, middle(), 2.0, 2.0, 5.0);
  const Eigen::VectorXd tau_test = noisy(w_test * truth, sigma, 24);
  const double fit_rms = rms(w_test * fit.parameters - tau_test), ols_rms = rms(w_test * ols - tau_test);
  EXPECT_LE(fit_rms, 1.05 * ols_rms) << "physical fit " << fit_rms << ", least squares " << ols_rms;
  // Much better in fact: the prior keeps what the data cannot tell (1.2 vs 25 here; 1.2 .. 2.0 sigma
  // over other seeds).
  EXPECT_LT(fit_rms, 2 * sigma) << "least squares " << ols_rms << ", the prior " << rms(w_test * prior - tau_test);
}

TEST_F(PhysicalFitArm7, MasslessPriorBodyIsProjectedAndTheFitStaysValid) {
  const Eigen::MatrixXd w = regressor(200, 31, middle(), 2.0, 2.0, 5.0);
  const Eigen::VectorXd tau = noisy(w * truth, 0.3, 32);
  Eigen::VectorXd massless = prior;
  massless.segment<10>(60).setZero();
  const batch::PhysicalFitResult fit = fitPhysicalParameters(batch::normalEquations(w, tau), massless);
  EXPECT_EQ(fit.projected_prior_bodies, std::vector<int>{6});
  EXPECT_TRUE(fit.success) << fit.status;
  EXPECT_TRUE(batch::allValid(fit.validity)) << batch::describeInvalid(fit.validity);
}

TEST_F(PhysicalFitArm7, CancelledFitStops) {
  const Eigen::MatrixXd w = regressor(200, 41, middle(), 2.0, 2.0, 5.0);
  const Eigen::VectorXd tau = noisy(w * truth, 0.3, 42);
  batch::PhysicalFitOptions options;
  int calls = 0;
  options.on_iteration = [&](const batch::IterationInfo& info) {
    ++calls;
    return info.iteration < 1;
  };
  const batch::PhysicalFitResult fit = fitPhysicalParameters(batch::normalEquations(w, tau), prior, options);
  EXPECT_TRUE(fit.cancelled);
  EXPECT_FALSE(fit.success);
  EXPECT_EQ(fit.status, "User_Requested_Stop");
  EXPECT_EQ(calls, 2);
  EXPECT_LE(fit.iterations, 1);
  EXPECT_TRUE(batch::allValid(fit.validity)) << batch::describeInvalid(fit.validity);
}

// Timings for the report (not run by default): arm7 with 1,000 and 10,000 samples.
TEST_F(PhysicalFitArm7, DISABLED_Timing) {
  for (int samples : {1000, 10000}) {
    const Eigen::MatrixXd w = regressor(samples, 51, middle(), 2.0, 2.0, 5.0);
    const Eigen::VectorXd tau = noisy(w * truth, 0.3, 52);
    const auto start = std::chrono::steady_clock::now();
    const batch::NormalEquations data = batch::normalEquations(w, tau);
    const double reduce = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const batch::PhysicalFitResult fit = fitPhysicalParameters(data, prior);
    std::printf("%d samples (%ld x %ld): normal equations %.4f s, setup %.4f s, Ipopt %.4f s, %d iterations, %s, "
                "residual RMS %.4f\n",
                samples, static_cast<long>(w.rows()), static_cast<long>(w.cols()), reduce, fit.setup_seconds,
                fit.seconds, fit.iterations, fit.status.c_str(), fit.residual_rms);
  }
}

}  // namespace
}  // namespace robodiff::testing
