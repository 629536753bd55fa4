// What the batch commands (trajectory, identify, trajopt) share: how their generated
// functions run. --backend compiled|interpreted, --cache DIR, --compiler CC, --threads N,
// and the BatchFunctionOptions they make.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "robodiff/batch/batch_function.hpp"

namespace robodiff::cli {

struct BatchFunctionArgs {
  std::string backend = "compiled";
  std::string cache_dir, compiler;
  unsigned threads = 0;
};

// Adds the four options; `what` names what the functions compute ("knots", "samples",
// "knots' dynamics") in their help. `with_threads`: false for a command that evaluates
// one knot at a time (its threads option would do nothing).
void addBatchFunctionOptions(CLI::App& cmd, BatchFunctionArgs& args, const std::string& what, bool with_threads = true);

// Backend, cache (--cache, else the default cache) for a compiled backend, compiler, threads.
batch::BatchFunctionOptions batchFunctionOptions(const BatchFunctionArgs& args);

}  // namespace robodiff::cli
