// What the trajectory tests share: the project's robots, specs, and trajectory files
// written from random states (the example data generator: nothing big is committed).
#pragma once

#include <charconv>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <gtest/gtest.h>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/trajectory_error.hpp"
#include "robodiff/batch/trajectory_table.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

inline constexpr const char* kRneaJacobian =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}]})";
// The same, compiled at -O0 for the generic target: the compiled tests' builds stay short.
inline constexpr const char* kRneaJacobianQuickBuild =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}],
        "build": {"optimization": "O0", "march_native": false}})";

inline std::string shortest(double x) {
  char buffer[32];
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, x).ptr);
}

struct Robot {
  std::filesystem::path urdf_path;
  std::string urdf;
  bool floating_base = false;
  Model model;

  explicit Robot(const std::string& name, bool floating = false)
      : urdf_path(sourceDir() / "examples/robots" / (name + ".urdf")),
        urdf(readFile(urdf_path)),
        floating_base(floating),
        model(loadUrdfString(urdf, floating ? RootJoint::FreeFlyer : RootJoint::Fixed, name + ".urdf")) {}

  batch::BatchFunction open(const FunctionSpec& spec, batch::Backend backend, const std::filesystem::path& cache,
                            unsigned threads = 2) const {
    batch::BatchFunctionOptions options;
    options.backend = backend;
    options.cache_dir = cache;
    options.worker_executable = workerPath();
    options.threads = threads;
    return batch::BatchFunction::open(model, urdf, floating_base, spec, options);
  }
};

// The random states of knots 1..knots (seed = knot number), each the spec's variable inputs.
inline std::vector<std::vector<Eigen::VectorXd>> randomKnots(const Model& model, const FunctionSpec& spec,
                                                             std::uint64_t knots) {
  std::vector<std::vector<Eigen::VectorXd>> states;
  for (std::uint64_t k = 1; k <= knots; ++k) states.push_back(randomRuntimeInputs(model, spec, k));
  return states;
}

// A CSV with t and the blocks' columns by joint name (or by index with `by_index`, and
// for blocks that are not per joint), one row per state; `extra` columns with text are
// added to show that unused columns are ignored.
inline std::string trajectoryCsv(const Model& model, const batch::BatchFunction& f,
                                 const std::vector<std::vector<Eigen::VectorXd>>& states, bool by_index = false) {
  std::ostringstream csv;
  csv << "t";
  for (const batch::BlockLayout& block : f.inputs()) {
    std::vector<std::string> names = by_index ? batch::indexColumns(block) : batch::jointColumns(model, block);
    if (names.empty()) names = batch::indexColumns(block);
    for (const std::string& name : names) csv << "," << name;
  }
  csv << ",note\n";
  for (std::size_t k = 0; k < states.size(); ++k) {
    csv << shortest(0.01 * static_cast<double>(k));
    for (const Eigen::VectorXd& block : states[k])
      for (Eigen::Index i = 0; i < block.size(); ++i) csv << "," << shortest(block[i]);
    csv << ",knot " << k << "\n";
  }
  return csv.str();
}

// The message of the TrajectoryError `parse` throws; fails the test when none is thrown.
template <typename F>
std::string errorOf(F&& parse) {
  try {
    parse();
  } catch (const batch::TrajectoryError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no TrajectoryError";
  return "";
}

}  // namespace robodiff::testing
