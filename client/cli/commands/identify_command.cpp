// `robodiff identify`: inertial parameter identification from measured samples (q, v, a,
// tau; CSV) (batch/identification): the regressor generated like any other function
// (compiled through the cache, or interpreted) and stacked over the samples, OLS or WLS on
// the base parameters or the physically consistent fit with Ipopt (--physical), residuals
// on fit and held-out samples, the validity of every body, and a URDF with the identified
// inertials.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "options/batch_function_options.hpp"
#include "service/service_helpers.hpp"
#include "robodiff/batch/atomic_file.hpp"
#include "commands/commands.hpp"
#include "options/function_options.hpp"
#include "output/output_table.hpp"
#include "robodiff/batch/identification.hpp"
#include "robodiff/batch/identification_json.hpp"
#include "robodiff/batch/measured_samples.hpp"
#include "robodiff/batch/physical_identification.hpp"
#include "robodiff/batch/urdf_inertials.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::cli {
namespace {

struct IdentifyArgs {
  RobotArgs robot;
  std::string data, out_urdf;
  BatchFunctionArgs function;
  double holdout = 0.0;
  double regularization = batch::PhysicalFitOptions{}.regularization;
  bool weighted = false, physical = false, json = false;
};

std::string fixed(double x, const char* format = "%.6g") {
  if (!std::isfinite(x)) return "-";
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, format, x);
  return buffer;
}

struct UrdfOutcome {
  std::optional<batch::UrdfRewrite> rewrite;
  std::string error;
};

UrdfOutcome writeUrdf(const IdentifyArgs& args, const batch::IdentificationProblem& problem,
                      const batch::IdentificationResult& result) {
  UrdfOutcome outcome;
  if (args.out_urdf.empty()) return outcome;
  try {
    outcome.rewrite =
        batch::rewriteUrdfInertials(problem.urdf_text, problem.urdf_source, problem.model, result.parameters);
    batch::AtomicFile out(args.out_urdf);  // all or nothing: never half a URDF
    out.write(outcome.rewrite->text);
    out.commit();
  } catch (const std::exception& e) {
    outcome.rewrite.reset();
    outcome.error = std::string("--out-urdf ") + args.out_urdf + ": " + e.what();
  }
  return outcome;
}

std::string methodName(const batch::IdentificationResult& result) {
  if (result.method == "physical") return "physically consistent fit (Ipopt)";
  return result.method == "wls" ? "weighted least squares" : "ordinary least squares";
}

void printTables(const IdentifyArgs& args, const batch::IdentificationProblem& problem,
                 const batch::IdentificationResult& result, const UrdfOutcome& urdf, double total_seconds) {
  const batch::BaseParameters& base = problem.base;
  std::cout << "identify " << (problem.model.name.empty() ? args.robot.urdf : problem.model.name) << ": "
            << problem.model.njoints() << " bodies, " << base.standard_count << " standard -> " << base.size()
            << " base parameters; " << methodName(result) << " on " << problem.fit.samples() << " samples, "
            << problem.held_out.samples() << " held out\n\n";

  std::cout << "Base parameters (identifiable combinations; units kg, kg m, kg m^2)\n";
  Table params = Table::rows({"#", "value", "std error", "rel. std %", "URDF", "base parameter"},
                             {true, true, true, true, true, false});
  for (int k = 0; k < base.size(); ++k)
    params.addRow({std::to_string(k + 1), fixed(result.base_values[k]), fixed(result.base_std_errors[k], "%.3g"),
                   fixed(result.base_relative_std[k], "%.3g"), fixed(result.base_prior[k]),
                   base.describe(k, problem.layout)});
  params.print(std::cout);

  std::cout << "\nResidual RMS per joint (N m or N): identified and URDF parameters\n";
  Table rms = Table::rows({"joint", "fit", "held-out", "URDF fit", "URDF held-out", "noise estimate"},
                          {false, true, true, true, true, true});
  const std::vector<std::string> labels = batch::jointLabels(problem.model);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const auto j = static_cast<Eigen::Index>(i);
    rms.addRow({labels[i], fixed(result.rms_fit[j], "%.4g"), fixed(result.rms_held_out[j], "%.4g"),
                fixed(result.rms_prior_fit[j], "%.4g"), fixed(result.rms_prior_held_out[j], "%.4g"),
                fixed(result.joint_sigma[j], "%.4g")});
  }
  rms.print(std::cout);

  std::cout << "\nIdentified bodies (composite per joint; what the data cannot see keeps the URDF's values)\n";
  Table bodies = Table::rows({"link", "mass", "com x", "com y", "com z", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz",
                              "consistent", "merged links"},
                             {false, true, true, true, true, true, true, true, true, true, true, false, false});
  for (std::size_t j = 0; j < result.bodies.size(); ++j) {
    const batch::BodyInertial b = batch::inertialFromParameters(result.bodies[j].parameters);
    std::string merged;
    for (const std::string& m : problem.layout.bodies[j].merged_links) merged += (merged.empty() ? "" : " ") + m;
    bodies.addRow({problem.layout.bodies[j].link, fixed(b.mass, "%.5g"), fixed(b.com.x(), "%.4g"),
                   fixed(b.com.y(), "%.4g"), fixed(b.com.z(), "%.4g"), fixed(b.inertia(0, 0), "%.4g"),
                   fixed(b.inertia(1, 1), "%.4g"), fixed(b.inertia(2, 2), "%.4g"), fixed(b.inertia(0, 1), "%.3g"),
                   fixed(b.inertia(0, 2), "%.3g"), fixed(b.inertia(1, 2), "%.3g"),
                   result.bodies[j].validity.valid ? "yes" : "NO", merged});
  }
  bodies.print(std::cout);

  std::cout << "\nPhysical validity per body (principal moments about the centre of mass, kg m^2)\n";
  Table validity = Table::rows({"link", "valid", "mass", "moment 1", "moment 2", "moment 3", "triangle margin",
                                "min eig. pseudo-inertia"},
                               {false, false, true, true, true, true, true, true});
  for (std::size_t j = 0; j < result.bodies.size(); ++j) {
    const batch::BodyValidity& v = result.bodies[j].validity;
    validity.addRow({problem.layout.bodies[j].link, v.valid ? "yes" : "NO", fixed(v.mass, "%.5g"),
                     fixed(v.principal_moments[0], "%.4g"), fixed(v.principal_moments[1], "%.4g"),
                     fixed(v.principal_moments[2], "%.4g"), fixed(v.triangle_margin, "%.4g"),
                     fixed(v.pseudo_inertia_min_eigenvalue, "%.4g")});
  }
  validity.print(std::cout);

  if (const std::optional<batch::SolverReport>& s = result.solver) {
    std::cout << "\nIpopt: " << s->status << (s->success ? "" : " (not converged)") << ", " << s->iterations
              << " iterations, " << fixed(s->seconds, "%.3f") << " s; regularization "
              << fixed(s->regularization, "%.3g") << ", weighting " << s->weighting
              << (s->weighting == "ols" ? ", residual RMS " : ", weighted residual RMS ")
              << fixed(s->residual_rms, "%.4g") << ", " << problem.fit.W.rows() << " equations\n";
  } else {
    std::cout << "\nsigma " << fixed(result.sigma, "%.4g") << ", condition number "
              << fixed(result.condition_number, "%.4g") << ", " << problem.fit.W.rows() << " equations\n";
  }
  std::cout << "\nTime\n";
  Table times = Table::rows({"phase", "seconds"}, {false, true});
  for (const batch::PhaseTime& t : result.times) times.addRow({t.phase, fixed(t.seconds, "%.4f")});
  times.addRow({"total", fixed(total_seconds, "%.4f")});
  times.print(std::cout);

  if (!problem.ignored_columns.empty()) {
    std::cout << "\nignored columns:";
    for (const std::string& c : problem.ignored_columns) std::cout << " " << c;
    std::cout << "\n";
  }
  for (const std::string& w : result.warnings) std::cout << "warning: " << w << "\n";
  if (urdf.rewrite) {
    std::cout << "\nwrote " << args.out_urdf << ": identified inertials on " << urdf.rewrite->written.size()
              << " links";
    if (!urdf.rewrite->zeroed.empty()) {
      std::cout << "; merged links zeroed (their inertia is in their carrier's):";
      for (const std::string& z : urdf.rewrite->zeroed) std::cout << " " << z;
    }
    std::cout << "\n";
  }
}

void identify(const IdentifyArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  if (!(args.holdout >= 0.0 && args.holdout < 1.0))
    throw std::invalid_argument("--holdout " + std::to_string(args.holdout) + ": must be in [0, 1)");
  if (!(args.regularization >= 0.0) || !std::isfinite(args.regularization))
    throw std::invalid_argument("--regularization " + std::to_string(args.regularization) +
                                ": must be finite and >= 0");
  batch::IdentificationOptions options;
  options.holdout = args.holdout;
  options.weighted = args.weighted;
  options.function = batchFunctionOptions(args.function);
  if (!args.json)
    options.function.on_progress = [](const std::string& what) {
      if (what == "building") std::cerr << "building the regressor (once per robot; cached afterwards)...\n";
    };

  const std::string urdf_text = readTextFile(args.robot.urdf, "--urdf");
  const Model model =
      loadUrdfString(urdf_text, args.robot.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed, args.robot.urdf);
  const auto read_start = std::chrono::steady_clock::now();
  const batch::MeasuredSamples samples = batch::readMeasuredSamples(args.data, model);
  const double read_seconds = batch::secondsSince(read_start);

  const batch::IdentificationProblem problem =
      batch::prepareIdentification(model, urdf_text, args.robot.urdf, args.robot.floating_base, samples, options);
  batch::PhysicalFitOptions physical;
  physical.regularization = args.regularization;
  batch::IdentificationResult result = args.physical ? batch::identifyPhysical(problem, options, physical)
                                                     : batch::identifyLeastSquares(problem, options);
  result.times.insert(result.times.begin(), {"reading samples", read_seconds});
  const UrdfOutcome urdf = writeUrdf(args, problem, result);
  const double total = batch::secondsSince(start);

  if (args.json) {
    nlohmann::json out = batch::identificationJson(problem, result);
    out["total_seconds"] = total;
    out["backend"] = batch::toString(options.function.backend);
    if (!args.out_urdf.empty()) {
      out["out_urdf"] = {{"path", args.out_urdf}, {"written", urdf.rewrite.has_value()}};
      if (urdf.rewrite) {
        out["out_urdf"]["links"] = urdf.rewrite->written;
        out["out_urdf"]["zeroed"] = urdf.rewrite->zeroed;
      } else {
        out["out_urdf"]["error"] = urdf.error;
      }
    }
    std::cout << out.dump() << "\n";
  } else {
    printTables(args, problem, result, urdf, total);
  }
  if (!urdf.error.empty()) throw std::runtime_error(urdf.error);
}

}  // namespace

void addIdentifyCommand(CLI::App& app) {
  auto args = std::make_shared<IdentifyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "identify", "Identify inertial parameters from measured samples (least squares, or physically consistent)");
  addRobotOptions(*cmd, args->robot);
  cmd->add_option("--data", args->data,
                  "Measured samples, CSV: a header naming the columns q_<joint>, v_<joint>, a_<joint>, tau_<joint> "
                  "for every moving joint (any order; optional t; other columns ignored), one row per sample")
      ->required()
      ->type_name("SAMPLES.csv");
  cmd->add_option("--holdout", args->holdout,
                  "Fraction of the samples held out of the fit, the LAST ones (default 0): their residual RMS tells "
                  "how the identified model predicts motion it has not seen");
  cmd->add_flag("--weighted", args->weighted,
                "Weighted least squares: each joint's rows weighted by 1/sigma_j, its noise estimated from the "
                "ordinary fit's residuals (one iteration); with --physical, the same noise estimate weights the "
                "physical fit's rows by 1/sigma_j^2");
  CLI::Option* physical = cmd->add_flag(
      "--physical", args->physical,
      "Physically consistent identification with Ipopt: every body keeps a positive mass, a positive definite "
      "inertia about its centre of mass and the triangle inequalities, however poor the data; the fit of all the "
      "standard parameters is pulled towards the URDF's values (--regularization), so what the data cannot tell "
      "stays near the URDF. Its identified URDF is always writable");
  cmd->add_option("--regularization", args->regularization,
                  "With --physical: the pull towards the URDF's values, as the cost (relative to the torques' sum of "
                  "squares) of moving a parameter by its body's own size (default " +
                      fixed(batch::PhysicalFitOptions{}.regularization, "%g") +
                      "); 0 leaves unexcited directions free")
      ->needs(physical)
      ->type_name("LAMBDA");
  cmd->add_option("--out-urdf", args->out_urdf,
                  "Write the URDF with the identified inertials (each joint's composite body on its child link, links "
                  "fixed to it zeroed; everything else unchanged)")
      ->type_name("FILE");
  cmd->add_flag("--json", args->json,
                "Print the result as JSON (base parameters, bodies and their validity, residuals, times; Ipopt's run "
                "with --physical)");
  addBatchFunctionOptions(*cmd, args->function, "sample (the regressor)");
  cmd->footer(
      "Base parameters are the combinations of standard parameters (per body: m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, "
      "Iyz, Izz about the joint frame's origin) that joint torques determine, found by QR with column pivoting. "
      "Least squares estimates them and completes the standard parameters towards the URDF's; --physical fits the "
      "standard parameters directly (log-Cholesky coordinates, Ipopt) and reports Ipopt's status, iterations and "
      "time. Every body's physical validity is reported. Exit status: 0 done, 1 an error (bad file, samples that do "
      "not excite the parameters for least squares, an identified body the URDF cannot hold).");
  cmd->callback([args] { identify(*args); });
}

}  // namespace robodiff::cli
