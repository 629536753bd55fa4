#pragma once
// Measured samples for identification: joint positions, velocities, accelerations and
// torques at N instants, read from (and written to) CSV.
//
// CSV format: a header row, then one row per sample, ',' between fields. Columns are
// named after the model's joints: q_<joint>, v_<joint>, a_<joint>, tau_<joint> for every
// moving joint, and an optional t (time, seconds). A free-flyer root joint has one column
// per coordinate: q_<joint>.x .y .z .qx .qy .qz .qw and v_/a_/tau_<joint>.vx .vy .vz .wx
// .wy .wz (as the CLI labels them). Columns may come in any order; other columns are
// ignored (and listed, by name). The file is read with batch/trajectory's CsvTable, the
// project's one CSV reader: '\n' or "\r\n" line ends, blank lines and lines starting with
// '#' (skipped), spaces and tabs around fields, header names in double quotes. Every field
// of a used column must be a finite number (nan and inf are rejected). Line numbers in
// messages are the file's physical lines, 1-based (the header is line 1 when nothing
// precedes it).

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/model/model.hpp"

namespace robodiff::batch {

struct MeasuredSamples {
  std::string source;        // the file name (or "<string>"), for messages
  Eigen::MatrixXd q;         // nq x N, sample k in column k
  Eigen::MatrixXd v, a, tau; // nv x N
  std::optional<Eigen::VectorXd> t;        // N, when the file has a t column
  std::vector<std::size_t> lines;          // per sample, its line in the file (0: not from a file)
  std::vector<std::string> ignored_columns;

  std::size_t size() const { return static_cast<std::size_t>(q.cols()); }
};

// The column names the samples of `model` use, in writing order: t (when `with_time`),
// then q, v, a and tau of every joint.
std::vector<std::string> sampleColumns(const Model& model, bool with_time = false);

// Parses CSV text. Throws IdentificationError "source:line: ..." naming the column and the
// text: a missing header, missing columns (all listed), a repeated column, a row with the
// wrong number of fields, a field that is not a finite number, no samples at all (the
// table's own errors are CsvTable's messages, as IdentificationErrors).
MeasuredSamples parseMeasuredSamples(const std::string& text, const Model& model, const std::string& source = "<string>");
MeasuredSamples readMeasuredSamples(const std::filesystem::path& path, const Model& model);

// Writes samples as CSV (every number with 17 significant digits, so that reading gives
// back the same doubles).
std::string formatMeasuredSamples(const MeasuredSamples& samples, const Model& model);
void writeMeasuredSamples(const std::filesystem::path& path, const MeasuredSamples& samples, const Model& model);

// Samples [begin, end) of `samples`.
MeasuredSamples sliceSamples(const MeasuredSamples& samples, std::size_t begin, std::size_t end);

}  // namespace robodiff::batch
