#pragma once
// Inertial parameter identification, the whole run:
//
//   prepareIdentification  the problem, independent of the estimator: the prior (the
//                          URDF's standard parameters), the base parameters, the samples
//                          split into fit and held-out parts and the regressor stacked
//                          over each (W, tau);
//   identifyLeastSquares   OLS or WLS on the base regressor (least_squares.hpp);
//   resultFor              the common report for any full parameter vector, so that
//                          other estimators (the physically consistent one with Ipopt,
//                          physical_identification.hpp) take the same problem and give
//                          the same kind of result.
//
// Hold-out: the LAST round(holdout * N) samples are held out (not fitted): measured
// samples are a time series, and a contiguous final stretch tests the model on motion it
// has not seen; every k-th sample would sit between fitted neighbours and tell little.
//
// From base to standard parameters: the identified vector is the one closest to the
// URDF's with the identified base parameters (BaseParameters::complete), distance measured
// in relative terms (each parameter divided by its size in the URDF, parameterScales):
// what the data cannot see keeps the URDF's values, so the result is a complete, usable
// set. (Least squares does not make it physically consistent; each body is checked, with
// batch/optimization's checkBodyValidity through inertialValidity, and reported.) A
// standard parameter's standard error is given only when the base parameters determine it
// on its own (BaseParameters::combinationFor); NaN otherwise.

#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "robodiff/batch/base_parameters.hpp"
#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/least_squares.hpp"
#include "robodiff/batch/measured_samples.hpp"
#include "robodiff/batch/parameter_layout.hpp"
#include "robodiff/batch/physical_validity.hpp"
#include "robodiff/batch/regressor_stack.hpp"

namespace robodiff::batch {

struct IdentificationOptions {
  double holdout = 0.0;           // fraction of the samples held out, in [0, 1)
  bool weighted = false;          // WLS instead of OLS
  BatchFunctionOptions function;  // the regressor's backend, cache, threads
  BaseParameterOptions base;
  double excitation_tolerance = 1e-10;  // LeastSquaresOptions::excitation_tolerance
  // Told each phase as it starts ("base parameters", "regressor", "stacking", ...).
  std::function<void(const std::string& phase)> on_phase;
};

struct PhaseTime {
  std::string phase;
  double seconds = 0;
};

// Everything an estimator needs; method-independent.
struct IdentificationProblem {
  Model model;                 // the prior model, loaded from the URDF
  std::string urdf_text;       // the URDF it was loaded from
  std::string urdf_source;     // its file name, for messages
  bool floating_base = false;
  ParameterLayout layout;      // names of the standard parameters, the links of each body
  Eigen::VectorXd prior;       // the URDF's standard parameters (10 per joint)
  Eigen::VectorXd scales;      // each standard parameter's size in the prior (parameterScales)
  BaseParameters base;
  RegressorStack fit;          // the fitted samples: tau = W pi
  RegressorStack held_out;     // the held-out samples (maybe none)
  std::string samples_source;
  std::vector<std::string> ignored_columns;
  std::vector<PhaseTime> times;
};

IdentificationProblem prepareIdentification(const Model& model, const std::string& urdf_text,
                                            const std::string& urdf_source, bool floating_base,
                                            const MeasuredSamples& samples, const IdentificationOptions& options = {});

// One body's identified inertia.
struct BodyResult {
  Eigen::Matrix<double, 10, 1> parameters, prior, std_errors;  // std_errors NaN where undefined
  BodyValidity validity;  // physical consistency (inertialValidity, urdf_inertials.hpp); message empty when valid
};

// What an iterative estimator's solver did (the physically consistent fit's Ipopt run).
struct SolverReport {
  std::string solver;           // "ipopt"
  bool success = false;         // converged (to tolerance or Ipopt's acceptable level)
  bool cancelled = false;
  std::string status;           // e.g. "Solve_Succeeded"
  int iterations = 0;
  double seconds = 0;           // the solve
  double setup_seconds = 0;     // building the program
  double regularization = 0;    // lambda, the pull towards the URDF's values
  std::string weighting;        // "ols" (every row 1) or "per-joint noise" (1/sigma_j^2 from an OLS pass)
  double residual_rms = 0;      // of the (weighted) fitted rows
  double regularization_term = 0;            // in the units of the weighted squared residual
  std::vector<int> projected_prior_bodies;   // prior bodies moved into the valid set to start from
};

struct IdentificationResult {
  std::string method;                   // "ols", "wls" or "physical"
  Eigen::VectorXd base_values;          // r
  Eigen::VectorXd base_prior;           // r, the URDF's
  Eigen::VectorXd base_std_errors;      // r (NaN when the method gives none)
  Eigen::VectorXd base_relative_std;    // r, percent
  Eigen::MatrixXd base_covariance;      // r x r (empty when none)
  Eigen::VectorXd parameters;           // n standard parameters, complete
  Eigen::VectorXd parameter_std_errors; // n, NaN where undefined
  std::vector<BodyResult> bodies;       // per joint
  Eigen::VectorXd joint_sigma;          // nv, the noise per joint estimated from the residuals
  double sigma = 0, condition_number = 0;
  Eigen::VectorXd rms_fit, rms_held_out;              // nv; held-out NaN when none
  Eigen::VectorXd rms_prior_fit, rms_prior_held_out;  // the URDF's, for comparison
  std::vector<std::string> warnings;
  std::vector<PhaseTime> times;         // the problem's phases, then the estimator's
  std::optional<SolverReport> solver;   // iterative estimators only
};

// OLS (or WLS with options.weighted). Throws IdentificationError when the samples do not
// excite every base parameter.
IdentificationResult identifyLeastSquares(const IdentificationProblem& problem, const IdentificationOptions& options = {});

// The report for a complete standard parameter vector found by any estimator: base
// values, residual RMS per joint on fit and held-out data, per-body values and
// validity. Statistics it cannot know (covariance, standard errors) are left NaN.
IdentificationResult resultFor(const IdentificationProblem& problem, const Eigen::VectorXd& parameters,
                               const std::string& method);

// The wall clock, for the phase times.
double secondsSince(const std::chrono::steady_clock::time_point& start);

// Runs `f` as phase `phase`: tells options.on_phase, appends its wall time to `times`, and
// returns what f returns.
template <class F>
auto timedPhase(std::vector<PhaseTime>& times, const IdentificationOptions& options, const std::string& phase, F&& f) {
  if (options.on_phase) options.on_phase(phase);
  const auto start = std::chrono::steady_clock::now();
  if constexpr (std::is_void_v<decltype(f())>) {
    f();
    times.push_back({phase, secondsSince(start)});
  } else {
    auto result = f();
    times.push_back({phase, secondsSince(start)});
    return result;
  }
}

// The base parameters' names (each its leading standard parameter), for messages.
std::vector<std::string> baseParameterNames(const IdentificationProblem& problem);

}  // namespace robodiff::batch
