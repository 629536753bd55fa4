#pragma once
// A function evaluated at every knot of a trajectory: BatchFunction::evaluateMany (all
// cores, the batched entry point of a compiled function), cancellable, with progress;
// and the whole job: read the trajectory, evaluate, write the outputs atomically.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/trajectory_output.hpp"
#include "robodiff/batch/trajectory_table.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

struct TrajectoryEvaluationOptions {
  std::function<bool()> cancelled;  // polled between pieces of knots (and of the output file)
  std::function<void(std::uint64_t done, std::uint64_t total)> progress;  // knots evaluated so far
};

struct TrajectoryEvaluation {
  TrajectoryOutput output;  // blocks, times and values; function/model/spec left to the caller
  double seconds = 0;       // evaluateMany's wall time
  // Knots with a NaN or infinite output (a singular configuration, ABA at a degenerate
  // inertia): counted, not an error; the first one's index.
  std::uint64_t non_finite_knots = 0;
  std::optional<std::uint64_t> first_non_finite_knot;

  double knotsPerSecond() const { return seconds > 0 ? static_cast<double>(output.knots) / seconds : 0.0; }
};

// Throws TrajectoryCancelled (nothing is returned), std::invalid_argument when the table
// was read for another input layout.
TrajectoryEvaluation evaluateTrajectory(const BatchFunction& function, const TrajectoryTable& table,
                                        const TrajectoryEvaluationOptions& options = {});

struct TrajectoryJob {
  std::filesystem::path data;          // CSV or JSON (trajectory_table.hpp)
  std::filesystem::path out;           // CSV or binary (trajectory_output.hpp)
  std::optional<OutputFormat> format;  // unset: by out's extension
  unsigned threads = 0;                // for writing CSV; 0: all cores (evaluation: the function's own)
  TrajectoryEvaluationOptions evaluation;
};

struct TrajectoryReport {
  std::filesystem::path data, out;
  OutputFormat format = OutputFormat::Csv;
  std::uint64_t knots = 0;
  double read_seconds = 0, evaluate_seconds = 0, write_seconds = 0;
  double knots_per_second = 0;  // evaluation alone
  std::uintmax_t bytes = 0;     // of the output file
  std::vector<std::string> ignored_columns;
  std::uint64_t non_finite_knots = 0;
  std::string first_non_finite;  // "traj.csv:17" (CSV) or "knot 15" (JSON); empty when none
};

// Reads job.data for `function` (its input blocks), evaluates every knot and writes job.out
// atomically. The binary header names spec's function, the model and the normalised spec.
// Throws TrajectoryError (file:line, column, text), TrajectoryCancelled (no file written).
TrajectoryReport runTrajectoryJob(const BatchFunction& function, const Model& model, const FunctionSpec& spec,
                                  const TrajectoryJob& job);

}  // namespace robodiff::batch
