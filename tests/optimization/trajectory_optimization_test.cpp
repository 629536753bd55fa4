// Trajectory optimisation on the project's own arm (examples/robots/arm7.urdf), checked
// against independent references: central finite differences of the objective, the
// constraints and the Lagrangian's gradient (the exact derivatives), core/dynamics' RNEA
// and the finite-difference definitions (the returned trajectory), the limits and the
// optimality inequalities (the solutions). The interpreted backend throughout (nothing
// to compile); the compiled one end to end through `robodiff trajopt`.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/batch/trajectory_optimization.hpp"
#include "robodiff/batch/trajectory_optimization_csv.hpp"
#include "robodiff/batch/trajectory_optimization_functions.hpp"
#include "robodiff/batch/trajectory_optimization_program.hpp"
#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using batch::TrajectoryOptimizationOptions;
using batch::TrajectoryOptimizationResult;
using batch::TrajectoryProgram;

std::filesystem::path arm7Path() { return sourceDir() / "examples" / "robots" / "arm7.urdf"; }

const Model& arm7() {
  static const Model model = loadUrdfFile(arm7Path().string());
  return model;
}

// Both functions, interpreted, built once for every test.
const batch::TrajectoryFunctions& interpretedFunctions() {
  static const batch::TrajectoryFunctions functions = [] {
    batch::BatchFunctionOptions options;
    options.backend = batch::Backend::Interpreted;
    return batch::TrajectoryFunctions::open(arm7(), readFile(arm7Path()), options);
  }();
  return functions;
}

// A configuration at `fraction` of every joint's range.
Eigen::VectorXd within(double fraction) {
  const Eigen::VectorXd lo = arm7().lowerPositionLimit(), hi = arm7().upperPositionLimit();
  return lo + fraction * (hi - lo);
}

TrajectoryOptimizationOptions smallProblem(int knots = 8) {
  TrajectoryOptimizationOptions o;
  o.knots = knots;
  o.duration = 1.5;
  o.torque_weight = 1e-2;
  o.q0 = within(0.3);
  o.qT = within(0.65);
  return o;
}

// Random interior knots near the middle of the joints' ranges; the ends at q0 and qT.
std::vector<double> randomTrajectory(const TrajectoryOptimizationOptions& o, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.3, 0.7);
  const int nv = arm7().nv;
  std::vector<double> x(static_cast<std::size_t>(o.knots) * nv);
  for (int k = 0; k < o.knots; ++k)
    for (int i = 0; i < nv; ++i) {
      const double lo = arm7().lowerPositionLimit()[i], hi = arm7().upperPositionLimit()[i];
      x[k * nv + i] = k == 0 ? o.q0[i] : k == o.knots - 1 ? o.qT[i] : lo + u(rng) * (hi - lo);
    }
  return x;
}

// Central differences of a vector function of x, column by column.
template <class F>
Eigen::MatrixXd centralDifferences(F f, std::vector<double> x, int rows, double step) {
  Eigen::MatrixXd d(rows, static_cast<Eigen::Index>(x.size()));
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double x0 = x[j];
    x[j] = x0 + step;
    const Eigen::VectorXd plus = f(x);
    x[j] = x0 - step;
    const Eigen::VectorXd minus = f(x);
    x[j] = x0;
    d.col(static_cast<Eigen::Index>(j)) = (plus - minus) / (2 * step);
  }
  return d;
}

Eigen::VectorXd gradientOf(TrajectoryProgram& p, const std::vector<double>& x) {
  Eigen::VectorXd g(p.variableCount());
  p.gradient(x, {g.data(), static_cast<std::size_t>(g.size())});
  return g;
}

Eigen::VectorXd constraintsOf(TrajectoryProgram& p, const std::vector<double>& x) {
  Eigen::VectorXd g(p.constraintCount());
  p.constraints(x, {g.data(), static_cast<std::size_t>(g.size())});
  return g;
}

// The constraint Jacobian as a dense matrix (entries summed where the pattern repeats).
Eigen::MatrixXd denseJacobian(TrajectoryProgram& p, const std::vector<double>& x) {
  const batch::SparsityEntries pattern = p.constraintJacobianPattern();
  std::vector<double> values(pattern.size());
  p.constraintJacobian(x, values);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(p.constraintCount(), p.variableCount());
  for (std::size_t e = 0; e < pattern.size(); ++e) J(pattern[e].first, pattern[e].second) += values[e];
  return J;
}

// The Hessian of the Lagrangian, full symmetric, from the lower-triangle entries.
Eigen::MatrixXd denseHessian(TrajectoryProgram& p, const std::vector<double>& x, double sigma,
                             const std::vector<double>& lambda) {
  const batch::SparsityEntries pattern = p.hessianPattern();
  std::vector<double> values(pattern.size());
  p.hessian(x, sigma, lambda, values);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(p.variableCount(), p.variableCount());
  for (std::size_t e = 0; e < pattern.size(); ++e) {
    const auto [r, c] = pattern[e];
    EXPECT_GE(r, c) << "entry " << e << " above the diagonal";
    H(r, c) += values[e];
    if (r != c) H(c, r) += values[e];
  }
  return H;
}

double maxAbs(const Eigen::MatrixXd& m) { return m.size() ? m.cwiseAbs().maxCoeff() : 0.0; }

TEST(TrajectoryOptimization, GradientMatchesCentralDifferencesOfTheObjective) {
  TrajectoryOptimizationOptions o = smallProblem(6);
  TrajectoryProgram program(arm7(), interpretedFunctions(), o);
  const std::vector<double> x = randomTrajectory(o, 7);
  const Eigen::VectorXd exact = gradientOf(program, x);
  const Eigen::MatrixXd fd = centralDifferences(
      [&](const std::vector<double>& y) { return Eigen::VectorXd::Constant(1, program.objective(y)); }, x, 1, 1e-6);
  const Eigen::VectorXd numeric = fd.row(0).transpose();
  ASSERT_GT(maxAbs(exact), 1.0);  // the check is not vacuous
  EXPECT_LT(maxAbs(exact - numeric), 1e-6 * (1 + maxAbs(exact))) << "exact\n"
                                                                  << exact.transpose() << "\nfd\n"
                                                                  << numeric.transpose();
  // The torque term alone, too (a tiny smoothness weight would hide it).
  o.smoothness_weight = 0;
  o.torque_weight = 1;
  TrajectoryProgram torque_only(arm7(), interpretedFunctions(), o);
  const Eigen::VectorXd exact_torque = gradientOf(torque_only, x);
  auto torque_objective = [&](const std::vector<double>& y) {
    return Eigen::VectorXd::Constant(1, torque_only.objective(y));
  };
  const Eigen::VectorXd numeric_torque = centralDifferences(torque_objective, x, 1, 1e-6).row(0).transpose();
  EXPECT_LT(maxAbs(exact_torque - numeric_torque), 1e-6 * (1 + maxAbs(exact_torque)));
}

// With torque limits the Lagrangian holds the constraints' second derivatives too: the
// Hessian is checked against differences of sigma grad f + J^T lambda at random lambda,
// over the whole matrix (so also that nothing lies outside the listed band).
TEST(TrajectoryOptimization, HessianMatchesDifferencesOfTheLagrangianGradient) {
  TrajectoryOptimizationOptions o = smallProblem(6);
  o.torque_limits = true;
  TrajectoryProgram program(arm7(), interpretedFunctions(), o);
  const std::vector<double> x = randomTrajectory(o, 11);
  ASSERT_GT(program.constraintCount(), program.velocityConstraintCount());  // torque rows exist

  // The constraint Jacobian against differences of the constraints.
  const Eigen::MatrixXd J = denseJacobian(program, x);
  auto constraints = [&](const std::vector<double>& y) { return constraintsOf(program, y); };
  const Eigen::MatrixXd J_fd = centralDifferences(constraints, x, program.constraintCount(), 1e-6);
  EXPECT_LT(maxAbs(J - J_fd), 1e-6 * (1 + maxAbs(J)));

  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> lambda(static_cast<std::size_t>(program.constraintCount()));
  for (double& l : lambda) l = u(rng);
  const double sigma = 0.7;
  const Eigen::Map<const Eigen::VectorXd> lambda_vector(lambda.data(), static_cast<Eigen::Index>(lambda.size()));
  auto lagrangian_gradient = [&](const std::vector<double>& y) -> Eigen::VectorXd {
    return sigma * gradientOf(program, y) + denseJacobian(program, y).transpose() * lambda_vector;
  };
  const Eigen::MatrixXd H = denseHessian(program, x, sigma, lambda);
  const Eigen::MatrixXd H_fd = centralDifferences(lagrangian_gradient, x, program.variableCount(), 1e-5);
  ASSERT_GT(maxAbs(H), 1.0);
  EXPECT_LT(maxAbs(H - H_fd), 1e-5 * (1 + maxAbs(H))) << "worst entry " << maxAbs(H - H_fd);

  // Without dynamics in the cost or the constraints the band is joint-diagonal and exact.
  o.torque_limits = false;
  o.torque_weight = 0;
  TrajectoryProgram smooth(arm7(), interpretedFunctions(), o);
  EXPECT_LT(smooth.hessianPattern().size(), program.hessianPattern().size());
  const Eigen::MatrixXd Hs = denseHessian(smooth, x, 1.0, {});
  const Eigen::MatrixXd Hs_fd = centralDifferences([&](const std::vector<double>& y) { return gradientOf(smooth, y); },
                                                   x, smooth.variableCount(), 1e-5);
  EXPECT_LT(maxAbs(Hs - Hs_fd), 1e-6 * (1 + maxAbs(Hs)));
}

// The returned knots against their definitions: v and a by the documented differences
// (rest at both ends), tau by core/dynamics' RNEA.
void expectConsistentTrajectory(const batch::Trajectory& t, double duration) {
  const Eigen::Index T = t.q.rows();
  const double h = duration / static_cast<double>(T - 1);
  Data<double> data(arm7());
  for (Eigen::Index k = 0; k < T; ++k) {
    SCOPED_TRACE("knot " + std::to_string(k));
    const Eigen::VectorXd prev = t.q.row(k == 0 ? 1 : k - 1).transpose();
    const Eigen::VectorXd next = t.q.row(k == T - 1 ? T - 2 : k + 1).transpose();
    const Eigen::VectorXd q = t.q.row(k).transpose();
    EXPECT_NEAR(t.time[k], static_cast<double>(k) * h, 1e-12);
    EXPECT_LT((t.v.row(k).transpose() - (next - prev) / (2 * h)).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((t.a.row(k).transpose() - (next - 2 * q + prev) / (h * h)).cwiseAbs().maxCoeff(), 1e-7);
    const Eigen::VectorXd tau = rnea(arm7(), data, q, Eigen::VectorXd(t.v.row(k).transpose()),
                                     Eigen::VectorXd(t.a.row(k).transpose()));
    EXPECT_LT((t.tau.row(k).transpose() - tau).cwiseAbs().maxCoeff(), 1e-8 * (1 + tau.cwiseAbs().maxCoeff()));
  }
  EXPECT_EQ(t.v.row(0).cwiseAbs().maxCoeff(), 0.0);  // at rest at both ends
  EXPECT_EQ(t.v.row(T - 1).cwiseAbs().maxCoeff(), 0.0);
}

// Every knot within the position limits, every velocity within the URDF's limits.
void expectWithinLimits(const batch::Trajectory& t, double tolerance) {
  const Eigen::VectorXd lo = arm7().lowerPositionLimit(), hi = arm7().upperPositionLimit(),
                        vmax = arm7().velocityLimit();
  for (Eigen::Index k = 0; k < t.q.rows(); ++k)
    for (int i = 0; i < arm7().nv; ++i) {
      EXPECT_GE(t.q(k, i), lo[i] - tolerance) << "knot " << k << " joint " << i;
      EXPECT_LE(t.q(k, i), hi[i] + tolerance) << "knot " << k << " joint " << i;
      EXPECT_LE(std::abs(t.v(k, i)), vmax[i] + tolerance) << "knot " << k << " joint " << i;
    }
}

TEST(TrajectoryOptimization, ConvergesFromAStraightLineWithinItsLimits) {
  const TrajectoryOptimizationOptions o = smallProblem(12);
  const TrajectoryOptimizationResult r = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  ASSERT_TRUE(r.success) << r.status;
  EXPECT_GT(r.iterations, 0);
  EXPECT_EQ(r.trajectory.q.rows(), o.knots);
  EXPECT_EQ(Eigen::VectorXd(r.trajectory.q.row(0).transpose()), o.q0);  // fixed ends, exactly
  EXPECT_EQ(Eigen::VectorXd(r.trajectory.q.row(o.knots - 1).transpose()), o.qT);
  expectWithinLimits(r.trajectory, 1e-6);
  EXPECT_LE(r.violation.position, 1e-6);
  EXPECT_LE(r.violation.velocity, 1e-6);
  EXPECT_LT(r.cost.total, r.initial_cost.total);
  EXPECT_NEAR(r.cost.total, r.cost.smoothness + r.cost.torque, 1e-12 * r.cost.total);
  expectConsistentTrajectory(r.trajectory, o.duration);
  EXPECT_GT(r.first_order_evaluations, 0);
  EXPECT_GT(r.second_order_evaluations, 0);
  EXPECT_GT(r.evaluation_seconds, 0);
  EXPECT_LE(r.evaluation_seconds, r.solve_seconds);
  // A local minimum: no interior variable moved a little, within the limits, lowers the
  // cost (moves that break an active limit are not candidates).
  TrajectoryProgram program(arm7(), interpretedFunctions(), o);
  std::vector<double> x(r.trajectory.q.size());
  for (int k = 0; k < o.knots; ++k)
    for (int i = 0; i < arm7().nv; ++i) x[k * arm7().nv + i] = r.trajectory.q(k, i);
  const double best = program.objective(x);
  const batch::LimitViolation at_best = program.violationAt(x);
  int candidates = 0;
  for (std::size_t j = arm7().nv; j + arm7().nv < x.size(); ++j)
    for (double step : {-1e-4, 1e-4}) {
      std::vector<double> y = x;
      y[j] += step;
      const batch::LimitViolation moved = program.violationAt(y);
      if (moved.position > at_best.position || moved.velocity > at_best.velocity) continue;
      ++candidates;
      EXPECT_GE(program.objective(y), best - 1e-9 * best) << "variable " << j << " moved by " << step;
    }
  EXPECT_GT(candidates, static_cast<int>(x.size()));  // most moves are feasible
}

// A fast move of one joint: the smooth optimum would exceed the joint's velocity limit
// (its peak is above the average speed, which is feasible); with the limits it touches it.
TEST(TrajectoryOptimization, VelocityLimitsBindWhereTheSmoothOptimumExceedsThem) {
  TrajectoryOptimizationOptions o = smallProblem(16);
  const int joint = 3;
  const double vmax = arm7().velocityLimit()[joint];
  o.duration = 1.0;
  o.torque_weight = 1e-4;
  o.q0 = o.qT = within(0.5);
  // Average speed 0.85 vmax (feasible); the smooth rest-to-rest optimum peaks near 1.5 times that.
  o.q0[joint] -= 0.65 * vmax * o.duration;
  o.qT[joint] += 0.2 * vmax * o.duration;

  o.velocity_limits = false;
  const TrajectoryOptimizationResult free = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  ASSERT_TRUE(free.success) << free.status;
  EXPECT_GT(free.trajectory.v.col(joint).cwiseAbs().maxCoeff(), 1.1 * vmax);
  EXPECT_GT(free.violation.velocity, 0.1 * vmax);

  o.velocity_limits = true;
  const TrajectoryOptimizationResult limited = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  ASSERT_TRUE(limited.success) << limited.status;
  expectWithinLimits(limited.trajectory, 1e-6);
  EXPECT_NEAR(limited.trajectory.v.col(joint).cwiseAbs().maxCoeff(), vmax, 1e-4);  // active
  EXPECT_GT(limited.cost.total, free.cost.total);  // the limit costs smoothness
  expectConsistentTrajectory(limited.trajectory, o.duration);
}

// sum_k c_k |tau_k|^2 of a trajectory (the cost's torque integral, unweighted).
double torqueIntegral(const batch::Trajectory& t) {
  const Eigen::Index T = t.tau.rows();
  const double h = t.time[1] - t.time[0];
  double sum = 0;
  for (Eigen::Index k = 0; k < T; ++k) sum += (k == 0 || k == T - 1 ? h / 2 : h) * t.tau.row(k).squaredNorm();
  return sum;
}

// With the smoothness optimum x_s (w = 0) and the optimum x_w of S + w T,
// S(x_w) >= S(x_s) and S(x_w) + w T(x_w) <= S(x_s) + w T(x_s), so T(x_w) <= T(x_s): a large
// torque weight must lower the torque integral, and here does so markedly by a new path.
TEST(TrajectoryOptimization, TorqueWeightTradesSmoothnessForLowerTorques) {
  TrajectoryOptimizationOptions o = smallProblem(12);
  o.duration = 2.0;
  o.torque_weight = 0;
  const TrajectoryOptimizationResult smooth = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  o.torque_weight = 0.05;
  const TrajectoryOptimizationResult weighted = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  ASSERT_TRUE(smooth.success) << smooth.status;
  ASSERT_TRUE(weighted.success) << weighted.status;
  EXPECT_EQ(smooth.cost.torque, 0.0);
  EXPECT_GE(weighted.cost.smoothness, smooth.cost.smoothness * (1 - 1e-9));
  const double t_smooth = torqueIntegral(smooth.trajectory), t_weighted = torqueIntegral(weighted.trajectory);
  EXPECT_LT(t_weighted, 0.95 * t_smooth) << "torque integrals " << t_weighted << " and " << t_smooth;
  EXPECT_GT((weighted.trajectory.q - smooth.trajectory.q).cwiseAbs().maxCoeff(), 1e-2);
  expectWithinLimits(weighted.trajectory, 1e-6);
}

// Effort limits below the unconstrained optimum's peak torque on one joint: enforced, the
// solution respects them (and the unconstrained one did not).
TEST(TrajectoryOptimization, TorqueLimitsAreEnforced) {
  TrajectoryOptimizationOptions o = smallProblem(12);
  o.duration = 1.0;
  const TrajectoryOptimizationResult free = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  ASSERT_TRUE(free.success) << free.status;
  // The joint whose torque varies most along the path gets a limit between its extremes
  // at the fixed ends and its peak.
  const Eigen::MatrixXd& tau = free.trajectory.tau;
  const Eigen::Index T = tau.rows();
  int joint = 0;
  double best_margin = 0, limit = 0;
  for (int i = 0; i < arm7().nv; ++i) {
    const double peak = tau.col(i).cwiseAbs().maxCoeff();
    const double ends = std::max(std::abs(tau(0, i)), std::abs(tau(T - 1, i)));
    if (peak - ends > best_margin) best_margin = peak - ends, joint = i, limit = ends + 0.6 * (peak - ends);
  }
  ASSERT_GT(best_margin, 0.1);
  o.torque_limits = true;
  o.effort_limit = Eigen::VectorXd::Constant(arm7().nv, std::numeric_limits<double>::infinity());
  o.effort_limit[joint] = limit;
  const TrajectoryOptimizationResult limited = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  ASSERT_TRUE(limited.success) << limited.status << " (joint " << joint << ", limit " << limit << ")";
  EXPECT_LE(limited.violation.torque, 1e-6);
  EXPECT_LE(limited.trajectory.tau.col(joint).cwiseAbs().maxCoeff(), limit + 1e-6);
  EXPECT_GT(limited.cost.total, free.cost.total);
  expectConsistentTrajectory(limited.trajectory, o.duration);
}

TEST(TrajectoryOptimization, CancelledFromTheIterationCallback) {
  TrajectoryOptimizationOptions o = smallProblem(8);
  int seen = 0;
  o.on_iteration = [&](const batch::IterationInfo& info) {
    ++seen;
    return info.iteration < 2;
  };
  const TrajectoryOptimizationResult r = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  EXPECT_TRUE(r.cancelled);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.status, "User_Requested_Stop");
  EXPECT_EQ(seen, 3);  // iterations 0, 1, 2
  EXPECT_EQ(r.trajectory.q.rows(), o.knots);
}

void expectRejected(const TrajectoryOptimizationOptions& o, const std::string& fragment) {
  try {
    batch::checkTrajectoryOptions(arm7(), o);
    ADD_FAILURE() << "accepted; expected a message with '" << fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(TrajectoryOptimization, RejectsOptionsThatDoNotFitTheRobotNamingTheField) {
  TrajectoryOptimizationOptions o = smallProblem();
  o.q0[2] = arm7().upperPositionLimit()[2] + 0.1;
  expectRejected(o, "q0: joint '" + arm7().joints[2].name + "'");
  o = smallProblem();
  o.qT.resize(3);
  expectRejected(o, "qT has 3 values");
  o = smallProblem();
  o.knots = 2;
  expectRejected(o, "knots = 2");
  o = smallProblem();
  o.duration = 0;
  expectRejected(o, "duration = 0");
  o = smallProblem();
  o.torque_weight = -1;
  expectRejected(o, "torque_weight = -1");
  o = smallProblem();
  o.initial_guess = Eigen::MatrixXd::Zero(o.knots + 1, arm7().nv);
  expectRejected(o, "initial_guess is 9 x 7");
  const Model floating = loadUrdfFile(arm7Path().string(), RootJoint::FreeFlyer);
  try {
    batch::checkTrajectoryOptions(floating, smallProblem());
    ADD_FAILURE() << "a floating base was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fixed-base"), std::string::npos) << e.what();
  }
}

// An initial guess replaces the straight line and reaches the same optimum.
TEST(TrajectoryOptimization, StartsFromAGivenInitialGuess) {
  TrajectoryOptimizationOptions o = smallProblem(8);
  const TrajectoryOptimizationResult straight = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  o.initial_guess.resize(o.knots, arm7().nv);
  for (int k = 0; k < o.knots; ++k) {
    const double s = static_cast<double>(k) / (o.knots - 1);
    o.initial_guess.row(k) = (o.q0 + s * s * (o.qT - o.q0)).transpose();  // a curve, not the line
  }
  const TrajectoryOptimizationResult guessed = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  ASSERT_TRUE(straight.success && guessed.success);
  EXPECT_NE(guessed.initial_cost.total, straight.initial_cost.total);
  EXPECT_NEAR(guessed.cost.total, straight.cost.total, 1e-6 * straight.cost.total);
  EXPECT_LT((guessed.trajectory.q - straight.trajectory.q).cwiseAbs().maxCoeff(), 1e-4);
}

std::vector<std::vector<std::string>> readCsv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::istringstream fields_in(line);
    std::string field;
    while (std::getline(fields_in, field, ',')) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

TEST(TrajectoryOptimization, CsvHoldsEveryKnotAndRoundTrips) {
  const TrajectoryOptimizationOptions o = smallProblem(5);
  const TrajectoryOptimizationResult r = batch::optimizeTrajectory(arm7(), interpretedFunctions(), o);
  TempDir tmp;
  const std::filesystem::path path = tmp / "trajectory.csv";
  batch::writeTrajectoryCsvFile(path, r.trajectory, arm7().jointNames());
  const auto rows = readCsv(readFile(path));
  const int nv = arm7().nv;
  ASSERT_EQ(rows.size(), 1u + o.knots);
  ASSERT_EQ(rows[0].size(), 1u + 4u * nv);
  EXPECT_EQ(rows[0][0], "t");
  EXPECT_EQ(rows[0][1], "q_" + arm7().joints[0].name);
  EXPECT_EQ(rows[0][1 + 3 * nv], "tau_" + arm7().joints[0].name);
  for (int k = 0; k < o.knots; ++k) {
    ASSERT_EQ(rows[k + 1].size(), rows[0].size());
    EXPECT_EQ(std::stod(rows[k + 1][0]), r.trajectory.time[k]);
    for (int i = 0; i < nv; ++i) {
      EXPECT_EQ(std::stod(rows[k + 1][1 + i]), r.trajectory.q(k, i));  // shortest round-trip form
      EXPECT_EQ(std::stod(rows[k + 1][1 + 3 * nv + i]), r.trajectory.tau(k, i));
    }
  }
  EXPECT_THROW(batch::writeTrajectoryCsvFile(tmp / "missing" / "t.csv", r.trajectory, arm7().jointNames()),
               std::runtime_error);
}

std::string commaList(const Eigen::VectorXd& v) {
  std::ostringstream out;
  out.precision(17);
  for (Eigen::Index i = 0; i < v.size(); ++i) out << (i ? "," : "") << v[i];
  return out.str();
}

std::string trajoptCommand(const std::filesystem::path& urdf, const Eigen::VectorXd& q0, const Eigen::VectorXd& qT,
                           const std::string& extra) {
  return shellQuote(cliPath().string()) + " trajopt --urdf " + shellQuote(urdf.string()) + " --q0 " +
         shellQuote(commaList(q0)) + " --qT " + shellQuote(commaList(qT)) + " " + extra;
}

// `robodiff trajopt` as a user runs it, compiled through a fresh cache (a 3-joint chain
// from make-robot: a small build), JSON summary and CSV file; its trajectory equals the
// library's through the interpreter.
TEST(TrajectoryOptimizationCli, OptimisesThroughTheCompiledBackendAndWritesCsv) {
  TempDir tmp;
  const std::filesystem::path urdf = tmp / "chain3.urdf";
  const ProcessResult made = runCommand(shellQuote(cliPath().string()) + " make-robot --chain 3 --seed 5 --out " +
                                        shellQuote(urdf.string()));
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const Model model = loadUrdfFile(urdf.string());
  const Eigen::VectorXd lo = model.lowerPositionLimit(), hi = model.upperPositionLimit();
  TrajectoryOptimizationOptions o;
  o.knots = 10;
  o.duration = 1.5;
  o.torque_weight = 1e-2;
  o.q0 = lo + 0.3 * (hi - lo);
  o.qT = lo + 0.7 * (hi - lo);

  const ProcessResult r = runCommand(trajoptCommand(urdf, o.q0, o.qT,
                                                    "--knots 10 --duration 1.5 --torque-weight 1e-2 --cache " +
                                                        shellQuote((tmp / "cache").string()) + " --out " +
                                                        shellQuote((tmp / "t.csv").string()) + " --json"));
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["success"], true);
  EXPECT_EQ(j["backend"], "compiled");
  EXPECT_GT(j["iterations"].get<int>(), 0);
  EXPECT_LE(j["max_violation"]["position"].get<double>(), 1e-6);
  EXPECT_LE(j["max_violation"]["velocity"].get<double>(), 1e-6);
  EXPECT_LT(j["cost"]["total"].get<double>(), j["initial_cost"]["total"].get<double>());

  batch::BatchFunctionOptions interpreted;
  interpreted.backend = batch::Backend::Interpreted;
  const TrajectoryOptimizationResult library = batch::optimizeTrajectory(model, readFile(urdf), o, interpreted);
  ASSERT_TRUE(library.success) << library.status;
  EXPECT_NEAR(j["cost"]["total"].get<double>(), library.cost.total, 1e-7 * library.cost.total);
  const auto rows = readCsv(readFile(tmp / "t.csv"));
  ASSERT_EQ(rows.size(), 11u);
  EXPECT_EQ(rows[0][1], "q_" + model.joints[0].name);
  for (int k = 0; k < o.knots; ++k)
    for (int i = 0; i < model.nv; ++i)
      EXPECT_NEAR(std::stod(rows[k + 1][1 + i]), library.trajectory.q(k, i), 1e-6) << "knot " << k << " joint " << i;
}

// The readable summary, the interpreter, the arm.
TEST(TrajectoryOptimizationCli, PrintsASummary) {
  const ProcessResult r =
      runCommand(trajoptCommand(arm7Path(), within(0.3), within(0.65), "--knots 10 --backend interpreted"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const char* part : {"Solve_Succeeded", "iterations", "cost", "smoothness", "max violation"})
    EXPECT_NE(r.out.find(part), std::string::npos) << part << " missing in\n" << r.out;
}

TEST(TrajectoryOptimizationCli, RejectsAConfigurationOutsideTheLimitsNamingTheJoint) {
  Eigen::VectorXd q0 = within(0.5);
  q0[4] = arm7().upperPositionLimit()[4] + 0.5;
  const ProcessResult r = runCommand(trajoptCommand(arm7Path(), q0, within(0.6), "--backend interpreted"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("q0: joint '" + arm7().joints[4].name + "'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("position limits"), std::string::npos) << r.err;
}

// Ipopt stopped early (one iteration): exit status 1, the summary still printed.
TEST(TrajectoryOptimizationCli, ExitsWithOneWhenIpoptDoesNotSucceed) {
  const ProcessResult r =
      runCommand(trajoptCommand(arm7Path(), within(0.2), within(0.8), "--backend interpreted --max-iter 1 --json"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["success"], false);
  EXPECT_EQ(j["status"], "Maximum_Iterations_Exceeded");
}

}  // namespace
}  // namespace robodiff::testing
