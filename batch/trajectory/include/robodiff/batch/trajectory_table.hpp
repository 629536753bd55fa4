#pragma once
// A trajectory read for one function: every knot's input blocks, concatenated in the
// layout of BatchFunction::inputs() (knot-major), ready for evaluateMany.
//
// CSV (header row, then one row per knot; csv_table.hpp says what is accepted):
//   t                optional; the knot's time, copied to the output as its first column
//                    (also accepted under the name "time").
//   q_<joint>        block q, one column per joint coordinate, named by the model's joints.
//                    A floating base (joint "root_joint") has seven:
//                    q_root_joint_x, _y, _z (position), _qx, _qy, _qz, _qw (unit quaternion).
//                    A user function's configuration inputs (q1, ...) are read the same
//                    way under their own names (q1_<joint>, ...).
//   v_<joint>, a_<joint>, tau_<joint>, weights_<joint>, u_<joint>
//                    any other input block of nv entries (a user function's by its name), one column per tangent
//                    coordinate; the floating base has six: <block>_root_joint_vx, _vy, _vz
//                    (linear), _wx, _wy, _wz (angular), as `robodiff compute` labels them.
//   <block>_<i>      any input block, by index i = 0 .. size-1 (q_0 .. q_6, weights_0 ...):
//                    the only naming for blocks that are not per joint (com's weights).
// Each block is read by joint names when all of them are in the header, else by indices
// when all of those are; anything else is an error naming the block and the columns it
// expected. Columns the function does not use (a measured torque, a fixed input, a label)
// are ignored and listed in `ignored_columns`; their fields are not parsed.
// Every used field must be a finite number; a floating base's quaternion must have norm 1
// (within 1e-5).
//
// JSON, one of two shapes (t optional in both; a block as an array of `size` numbers):
//   {"t": [t0, t1, ...], "q": [[...], [...], ...], "v": [[...], ...], ...}   block-major
//   [{"t": t0, "q": [...], "v": [...], ...}, {...}, ...]                      knot-major
// Other keys are ignored (and listed). Errors name the JSON path: "traj.json: q[17][3]: ...".

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/trajectory_output.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

struct TrajectoryTable {
  std::string source;                        // the file, as messages name it
  std::uint64_t knots = 0;
  std::size_t input_count = 0;               // doubles per knot (the function's inputCount())
  std::vector<double> inputs;                // knots x input_count, knot-major
  std::vector<double> times;                 // per knot; empty when the file has no t
  std::vector<std::uint64_t> lines;          // CSV: each knot's line; JSON: empty
  std::vector<std::string> ignored_columns;  // columns (keys) the function does not use
  // Per input block: the column names it was read from, in entry order.
  std::vector<std::vector<std::string>> block_columns;
};

// The input blocks that are configurations (nq entries, a floating base's quaternion
// checked): "q" for a model function, a user function's "configuration" inputs.
std::vector<std::string> configurationInputs(const FunctionSpec& spec);

// The columns an input block may be read from. `jointColumns` is empty for a block that
// is not per joint (neither a configuration with nq entries nor a block of nv entries).
std::vector<std::string> jointColumns(const Model& model, const BlockLayout& block,
                                      const std::vector<std::string>& configurations = {"q"});
std::vector<std::string> indexColumns(const BlockLayout& block);
// The model's velocity coordinates, one name each in v's order: the joint's name for a
// one-DoF joint, "<joint>_vx" .. "<joint>_wz" for a free flyer, "<joint>_<k>" otherwise.
std::vector<std::string> dofNames(const Model& model);

// The row and column names of each output block of `spec` (trajectory_output.hpp says
// which rows and columns are named); a block whose sizes do not fit gets none.
std::vector<AxisLabels> outputAxisLabels(const Model& model, const FunctionSpec& spec,
                                         const std::vector<BlockLayout>& inputs,
                                         const std::vector<BlockLayout>& outputs);

// Throws TrajectoryError ("source:line: ..." for CSV, "source: path: ..." for JSON).
// `configurations` names the configuration blocks (configurationInputs).
TrajectoryTable parseTrajectoryCsv(std::string text, const std::string& source, const Model& model,
                                   const std::vector<BlockLayout>& inputs,
                                   const std::vector<std::string>& configurations = {"q"});
TrajectoryTable parseTrajectoryJson(const std::string& text, const std::string& source, const Model& model,
                                    const std::vector<BlockLayout>& inputs,
                                    const std::vector<std::string>& configurations = {"q"});
// By extension: .json is JSON, anything else CSV.
TrajectoryTable readTrajectoryFile(const std::filesystem::path& path, const Model& model,
                                   const std::vector<BlockLayout>& inputs,
                                   const std::vector<std::string>& configurations = {"q"});

}  // namespace robodiff::batch
