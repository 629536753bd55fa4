// What `compute` and `eval` share for a user function (spec.user): its inputs read by
// name from the state file, and its outputs printed under the names the spec gives
// them (one JSON key, one table per output).
#pragma once

#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"
#include "output/spec_output.hpp"
#include "output/state_json.hpp"

namespace robodiff::cli {

// The function's input blocks (name, size, in order) as inputs read by name; a
// configuration is one the spec declares so.
std::vector<NamedInput> userNamedInputs(const FunctionSpec& spec,
                                        const std::vector<std::pair<std::string, int>>& blocks);

// The runtime inputs (one vector per block of `inputs`) from --state, read by name, or
// --random-state (randomRuntimeInputs), and the state's name for messages.
std::pair<std::vector<Eigen::VectorXd>, std::string> loadUserInputs(const StateArgs& args, const Model& model,
                                                                    const FunctionSpec& spec,
                                                                    const std::vector<NamedInput>& inputs);

// `meta` plus one key per output, its name: a value with one column, a gradient and a
// vector-Jacobian product as flat arrays, anything else [rows][cols] (sparse blocks
// expanded, a sparse Hessian mirrored). Throws when an output's name is a key of `meta`.
nlohmann::json userOutputsJson(nlohmann::json meta, const FunctionSpec& spec, const std::vector<Eigen::MatrixXd>& out);

// One table per output, titled "name (kind of EXPR)"; derivative columns (and the rows
// of gradients, vjps and Hessians) are labelled by input: "q:joint" for a
// configuration's or an nv-sized input's tangent coordinates, "x[i]" otherwise.
void printUserTables(std::ostream& os, const Model& model, const FunctionSpec& spec,
                     const std::vector<NamedInput>& inputs, const std::vector<Eigen::MatrixXd>& out);

}  // namespace robodiff::cli
