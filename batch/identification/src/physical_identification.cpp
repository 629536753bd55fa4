// identifyPhysical: the weights, the normal equations of the fitted samples, the Ipopt fit
// and its report.
#include "robodiff/batch/physical_identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/least_squares.hpp"

namespace robodiff::batch {
namespace {

constexpr Eigen::Index kSamplesPerBlock = 1024;  // rows copied to column-major at a time

// Ipopt's outcome as warnings: a stop short of convergence, a prior moved to start from.
std::vector<std::string> solverWarnings(const IdentificationProblem& problem, const PhysicalFitResult& fit) {
  std::vector<std::string> out;
  if (fit.cancelled)
    out.push_back("the physically consistent fit was cancelled after " + std::to_string(fit.iterations) +
                  " iterations: every body is valid, but the fit is not finished");
  else if (!fit.success)
    out.push_back("Ipopt stopped with status " + fit.status + " after " + std::to_string(fit.iterations) +
                  " iterations: every body is valid, but the fit may not be the optimum");
  for (int b : fit.projected_prior_bodies)
    out.push_back("the URDF's body of link '" + problem.layout.bodies.at(static_cast<std::size_t>(b)).link +
                  "' is not strictly physically valid: the fit started from a valid body next to it");
  return out;
}

}  // namespace

NormalEquations stackNormalEquations(const RegressorStack& stack, const Eigen::VectorXd& joint_weights) {
  const int nv = stack.nv;
  if (joint_weights.size() != 0 && joint_weights.size() != nv)
    throw IdentificationError("normal equations: " + std::to_string(joint_weights.size()) + " joint weights for " +
                              std::to_string(nv) + " joints");
  NormalEquations data(static_cast<int>(stack.W.cols()));
  const Eigen::Index block = kSamplesPerBlock * std::max(nv, 1);
  Eigen::VectorXd weights;
  for (Eigen::Index first = 0; first < stack.W.rows(); first += block) {
    const Eigen::Index rows = std::min(block, stack.W.rows() - first);
    if (joint_weights.size() != 0) {  // rows of one sample are its joints, in order
      weights.resize(rows);
      for (Eigen::Index i = 0; i < rows; ++i) weights[i] = joint_weights[(first + i) % nv];
    }
    data.add(stack.W.middleRows(first, rows), stack.tau.segment(first, rows), weights);
  }
  return data;
}

IdentificationResult identifyPhysical(const IdentificationProblem& problem, const IdentificationOptions& options,
                                      const PhysicalFitOptions& fit_options) {
  std::vector<PhaseTime> times;
  std::vector<std::string> warnings;
  const int nv = problem.fit.nv;
  Eigen::VectorXd joint_sigma = Eigen::VectorXd::Constant(nv, std::numeric_limits<double>::quiet_NaN());
  Eigen::VectorXd joint_weights;  // empty: every row 1
  if (options.weighted) {
    timedPhase(times, options, "noise per joint (least squares)", [&] {
      LeastSquaresOptions ls;
      ls.excitation_tolerance = options.excitation_tolerance;
      try {
        joint_sigma = solveLeastSquares(problem.base.baseColumns(problem.fit.W), problem.fit.tau, nv, ls,
                                        baseParameterNames(problem))
                          .joint_sigma;
        joint_weights = jointWeights(joint_sigma).cwiseAbs2();
      } catch (const IdentificationError& e) {
        warnings.push_back(std::string("no per-joint noise estimate, every row weighted 1: ") + e.what());
      }
    });
  }

  PhysicalFitResult fit;
  try {
    const NormalEquations data = timedPhase(times, options, "normal equations",
                                            [&] { return stackNormalEquations(problem.fit, joint_weights); });
    fit = timedPhase(times, options, "physically consistent fit (Ipopt)",
                     [&] { return fitPhysicalParameters(data, problem.prior, fit_options); });
  } catch (const std::invalid_argument& e) {
    throw IdentificationError(std::string("the physically consistent fit cannot start: ") + e.what());
  } catch (const IdentificationError&) {
    throw;
  } catch (const std::runtime_error& e) {  // Ipopt refused an option or could not start
    throw IdentificationError(std::string("the physically consistent fit cannot start: ") + e.what());
  }

  IdentificationResult result =
      timedPhase(times, options, "report", [&] { return resultFor(problem, fit.parameters, "physical"); });
  result.joint_sigma = joint_sigma;
  SolverReport& solver = result.solver.emplace();
  solver.solver = "ipopt";
  solver.success = fit.success;
  solver.cancelled = fit.cancelled;
  solver.status = fit.status;
  solver.iterations = fit.iterations;
  solver.seconds = fit.seconds;
  solver.setup_seconds = fit.setup_seconds;
  solver.regularization = fit_options.regularization;
  solver.weighting = joint_weights.size() != 0 ? "per-joint noise" : "ols";
  solver.residual_rms = fit.residual_rms;
  solver.regularization_term = fit.regularization_term;
  solver.projected_prior_bodies = fit.projected_prior_bodies;

  warnings.insert(warnings.begin(), result.warnings.begin(), result.warnings.end());
  const std::vector<std::string> from_solver = solverWarnings(problem, fit);
  warnings.insert(warnings.end(), from_solver.begin(), from_solver.end());
  result.warnings = std::move(warnings);
  result.times = problem.times;
  result.times.insert(result.times.end(), times.begin(), times.end());
  return result;
}

}  // namespace robodiff::batch
