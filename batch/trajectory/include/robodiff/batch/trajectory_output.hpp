#pragma once
// Writing (and reading back) a function's outputs at every knot of a trajectory.
//
// CSV (.csv): a header row, then one row per knot, numbers in the shortest form that reads
// back to the same double (std::to_chars). Columns: "t" when the trajectory had times,
// then one column per output double in the function's layout order:
//   <block>_<r>        a block with one column (value of rnea: value_<joint>)
//   <block>_<r>_<c>    a dense matrix block, row-major (jacobian_elbow_q_shoulder)
//   <block>_<r>_<c>    a CSR block: one column per stored nonzero, in CSR order
// A row or column is named by its joint coordinate where the block's rows are the
// model's nv velocity coordinates (a free flyer's root_joint_vx .. _wz, as the input CSV
// names them), and a Jacobian's or Hessian's column by the input it differentiates
// against, in the spec's "wrt" order: <input>_<joint> for an input per joint (a floating
// base's q block has nv tangent columns), <input>_<i> for another (a user function's
// gradient's entries too: grad_q_elbow); anything else by its
// 0-based number (fk's value_0 .. value_6).
//
// Binary (.rdb or .bin), for large outputs, read without parsing text:
//   offset 0    8 bytes  magic "RDTRAJ01"
//   offset 8    8 bytes  H, uint64 little-endian: the JSON header's length in bytes
//   offset 16   H bytes  the JSON header, UTF-8, padded with spaces so that the data
//                        starts at a multiple of 64 bytes
//   offset 16+H          knots x row_stride float64, little-endian, knot-major: row k is
//                        [t_k if has_time] then the output blocks at their offsets
// The JSON header:
//   {"format": "robodiff-trajectory", "version": 1, "byte_order": "little",
//    "dtype": "float64", "knots": N, "row_stride": S, "has_time": true,
//    "data_offset": 16+H, "function": "rnea", "model": "arm7", "spec": {...},
//    "blocks": [{"name": "value", "rows": 7, "cols": 1, "layout": "dense", "offset": 1,
//                "size": 7},
//               {"name": "jacobian", "rows": 7, "cols": 21, "layout": "csr", "offset": 8,
//                "size": NNZ, "row_ptr": [...], "col_idx": [...]}, ...]}
//   ("offset": the block's first double within a row, t included; "spec" only when known.)
//
// Either file is written atomically (atomic_file.hpp): a failed or cancelled write leaves
// nothing at the path (an older file there stays as it was).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "robodiff/batch/batch_function.hpp"

namespace robodiff::batch {

enum class OutputFormat { Csv, Binary };
const char* toString(OutputFormat format);          // "csv", "binary"
OutputFormat parseOutputFormat(const std::string& text);  // csv | binary | rdb | bin; throws std::invalid_argument
// By extension: .csv -> Csv, .rdb or .bin -> Binary; throws TrajectoryError naming the path otherwise.
OutputFormat outputFormatFor(const std::filesystem::path& path);

// Names of a block's rows and of its columns, as the CSV header uses them.
struct AxisLabels {
  std::vector<std::string> rows, cols;
};

struct TrajectoryOutput {
  std::vector<BlockLayout> blocks;  // the function's outputs(), offsets within one knot's outputs
  std::size_t output_count = 0;     // doubles per knot over all blocks
  std::uint64_t knots = 0;
  std::vector<double> times;        // per knot; empty: no t column
  std::vector<double> values;       // knots x output_count, knot-major
  std::string function, model;      // named in the binary header
  std::string spec_json;            // the normalised spec, in the binary header when set
  // Per block, names for its rows and columns (outputAxisLabels); a missing or empty
  // list: by index.
  std::vector<AxisLabels> labels;

  const double* knot(std::uint64_t k) const { return values.data() + k * output_count; }
};

// One name per output double, as the CSV header has them (without "t"): "<block>_<row>"
// for a vector, "<block>_<row>_<column>" for a matrix entry, each row and column by its
// label in `labels` (value_elbow, jacobian_elbow_v_shoulder) or else by its number.
std::vector<std::string> outputColumnNames(const std::vector<BlockLayout>& blocks,
                                           const std::vector<AxisLabels>& labels = {});

struct OutputWriteOptions {
  std::optional<OutputFormat> format;  // unset: by the path's extension
  unsigned threads = 0;                // formatting CSV numbers; 0: all cores
  std::function<bool()> cancelled;     // polled between pieces; true: TrajectoryCancelled, no file
};

// Throws TrajectoryError naming the path (an unknown extension, a directory that cannot be
// written, a full disk), TrajectoryCancelled.
void writeTrajectoryOutput(const std::filesystem::path& path, const TrajectoryOutput& output,
                           const OutputWriteOptions& options = {});

// Reads a binary file back (blocks with their CSR patterns, times, values; function,
// model and spec from the header). Throws TrajectoryError naming the path and what is
// wrong (magic, header, dtype, byte order, a size that does not match).
TrajectoryOutput readTrajectoryBinary(const std::filesystem::path& path);

}  // namespace robodiff::batch
