// The identification run: the problem (prior, base parameters, stacked regressors), the
// least-squares estimate, and the common report for any estimate.
#include "robodiff/batch/identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/urdf_inertials.hpp"

namespace robodiff::batch {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

std::vector<std::string> baseParameterNames(const IdentificationProblem& problem) {
  std::vector<std::string> names;
  for (int k = 0; k < problem.base.size(); ++k) names.push_back(problem.base.name(k, problem.layout));
  return names;
}

double secondsSince(const std::chrono::steady_clock::time_point& start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

IdentificationProblem prepareIdentification(const Model& model, const std::string& urdf_text,
                                            const std::string& urdf_source, bool floating_base,
                                            const MeasuredSamples& samples, const IdentificationOptions& options) {
  if (!(options.holdout >= 0.0 && options.holdout < 1.0))
    throw IdentificationError("the held-out fraction must be in [0, 1), not " + std::to_string(options.holdout));
  IdentificationProblem problem;
  problem.model = model;
  problem.urdf_text = urdf_text;
  problem.urdf_source = urdf_source;
  problem.floating_base = floating_base;
  problem.samples_source = samples.source;
  problem.ignored_columns = samples.ignored_columns;
  problem.layout = parameterLayout(model);
  problem.prior = modelParameters(model);
  problem.scales = parameterScales(problem.prior);
  problem.base = timedPhase(problem.times, options, "base parameters",
                       [&] { return computeBaseParameters(model, options.base); });

  const std::size_t n = samples.size();
  const auto held = static_cast<std::size_t>(std::llround(options.holdout * static_cast<double>(n)));
  const std::size_t fitted = n - held;
  const std::size_t needed = static_cast<std::size_t>(problem.base.size() / std::max(model.nv, 1)) + 1;
  if (fitted < needed)
    throw IdentificationError(samples.source + ": " + std::to_string(fitted) + " samples to fit (of " +
                              std::to_string(n) + ", " + std::to_string(held) + " held out) cannot determine " +
                              std::to_string(problem.base.size()) + " base parameters; at least " +
                              std::to_string(needed) + " are needed, many more for a useful fit");

  const BatchFunction regressor = timedPhase(problem.times, options, "regressor function", [&] {
    return openRegressor(model, urdf_text, floating_base, options.function);
  });
  timedPhase(problem.times, options, "stacking the regressor", [&] {
    problem.fit = stackRegressor(regressor, model, samples, 0, fitted);
    problem.held_out = stackRegressor(regressor, model, samples, fitted, n);
  });
  return problem;
}

IdentificationResult resultFor(const IdentificationProblem& problem, const Eigen::VectorXd& parameters,
                               const std::string& method) {
  const BaseParameters& base = problem.base;
  const int nv = problem.model.nv, r = base.size(), n = base.standard_count;
  if (parameters.size() != n)
    throw IdentificationError("a result needs " + std::to_string(n) + " standard parameters, not " +
                              std::to_string(parameters.size()));
  IdentificationResult result;
  result.method = method;
  result.parameters = parameters;
  result.base_values = base.fromStandard(parameters);
  result.base_prior = base.fromStandard(problem.prior);
  result.base_std_errors = result.base_relative_std = Eigen::VectorXd::Constant(r, kNaN);
  result.parameter_std_errors = Eigen::VectorXd::Constant(n, kNaN);
  result.joint_sigma = Eigen::VectorXd::Constant(nv, kNaN);
  result.sigma = result.condition_number = kNaN;

  auto rms = [&](const RegressorStack& stack, const Eigen::VectorXd& pi) {
    if (stack.W.rows() == 0) return Eigen::VectorXd::Constant(nv, kNaN).eval();
    return jointRms(stack.tau - stack.W * pi, nv);
  };
  result.rms_fit = rms(problem.fit, parameters);
  result.rms_held_out = rms(problem.held_out, parameters);
  result.rms_prior_fit = rms(problem.fit, problem.prior);
  result.rms_prior_held_out = rms(problem.held_out, problem.prior);
  if (problem.held_out.W.rows() == 0) result.warnings.push_back("no held-out samples: the held-out RMS is not known");

  for (int j = 0; j < problem.model.njoints(); ++j) {
    BodyResult body;
    body.parameters = parameters.segment<10>(kParametersPerBody * j);
    body.prior = problem.prior.segment<10>(kParametersPerBody * j);
    body.std_errors.setConstant(kNaN);
    body.validity = inertialValidity(body.parameters);
    if (!body.validity.valid)
      result.warnings.push_back("body of link '" + problem.layout.bodies[static_cast<std::size_t>(j)].link +
                                "' is not physically consistent: " + body.validity.message);
    result.bodies.push_back(body);
  }
  return result;
}

IdentificationResult identifyLeastSquares(const IdentificationProblem& problem, const IdentificationOptions& options) {
  std::vector<PhaseTime> times;
  LeastSquaresOptions ls;
  ls.weighted = options.weighted;
  ls.excitation_tolerance = options.excitation_tolerance;
  const std::string phase = options.weighted ? "weighted least squares" : "least squares";
  const LeastSquaresFit fit = timedPhase(times, options, phase, [&] {
    return solveLeastSquares(problem.base.baseColumns(problem.fit.W), problem.fit.tau, problem.fit.nv, ls,
                             baseParameterNames(problem));
  });
  IdentificationResult result = timedPhase(times, options, "report", [&] {
    const Eigen::VectorXd parameters = problem.base.complete(fit.theta, problem.prior, problem.scales);
    IdentificationResult r = resultFor(problem, parameters, options.weighted ? "wls" : "ols");
    r.base_values = fit.theta;  // exact, not recomputed through B
    r.base_std_errors = fit.std_errors;
    r.base_relative_std = fit.relative_std;
    r.base_covariance = fit.covariance;
    r.joint_sigma = fit.joint_sigma;
    r.sigma = fit.sigma;
    r.condition_number = fit.condition_number;
    for (int i = 0; i < problem.base.standard_count; ++i)
      if (const std::optional<Eigen::VectorXd> c = problem.base.combinationFor(i))
        r.parameter_std_errors[i] = std::sqrt(std::max(0.0, c->dot(fit.covariance * *c)));
    for (std::size_t j = 0; j < r.bodies.size(); ++j)
      r.bodies[j].std_errors = r.parameter_std_errors.segment<10>(kParametersPerBody * static_cast<Eigen::Index>(j));
    return r;
  });
  if (result.condition_number > 1e6)
    result.warnings.push_back("the base regressor is poorly conditioned (condition number " +
                              std::to_string(result.condition_number) +
                              "): some base parameters are weakly excited, see their relative standard deviations");
  result.times = problem.times;
  result.times.insert(result.times.end(), times.begin(), times.end());
  return result;
}

}  // namespace robodiff::batch
