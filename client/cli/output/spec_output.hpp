// What `compute` and `eval` share: the state to evaluate at (--state FILE or
// --random-state SEED), a spec's outputs as JSON ({"function", "backend", "nq", "nv",
// "value", "jacobian", ...}) and as tables. Both print the same shapes, so that a
// service's answer can be compared with a local one.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"
#include "output/state_json.hpp"

namespace robodiff::cli {

nlohmann::json toJson(const Eigen::MatrixXd& m);  // [rows][cols]
nlohmann::json toJson(const Eigen::VectorXd& v);  // [n]

// One label per velocity coordinate: the joint name, or name.vx ... name.wz.
std::vector<std::string> velocityLabels(const Model& model);

// --state FILE | --random-state SEED.
struct StateArgs {
  std::string path;
  std::optional<std::uint64_t> seed;
};
void addStateOptions(CLI::App& cmd, StateArgs& args);

// The state to evaluate at and its name for messages (the file, or the seed); a random
// state draws `weight_count` Hessian weights too. Throws std::invalid_argument when
// neither option was given.
std::pair<State, std::string> loadState(const StateArgs& args, const Model& model, int weight_count = 0);

// What printing needs of one output block of a spec's function.
struct OutputBlockInfo {
  std::string name;  // as in the library: value, jacobian, jacobian_q, hessian, ...
  OutputKind kind = OutputKind::Value;
  std::vector<std::string> wrt;  // Jacobian / Hessian
};

// {"function": label, "backend", "nq", "nv", ["frame"], ["reference"], and one key per
// output block: the value as a vector when it has one column, else [rows][cols]}.
nlohmann::json specOutputsJson(const std::string& label, const std::string& backend, const Model& model,
                               const FunctionSpec& spec, const std::vector<OutputBlockInfo>& blocks,
                               const std::vector<Eigen::MatrixXd>& out);

// One table per output block, rows and columns labelled by joint where they can be.
void printSpecTables(std::ostream& os, const Model& model, const FunctionSpec& spec,
                     const std::vector<OutputBlockInfo>& blocks, const std::vector<Eigen::MatrixXd>& out);

}  // namespace robodiff::cli
