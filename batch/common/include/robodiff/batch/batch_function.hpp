#pragma once
// A generated function for batch work (trajectories, identification, optimisation):
// the spec built for the model, evaluated many times from one process on all cores.
//
// Backends:
//   Compiled    - the compiled library from the shared cache; built first when missing
//                 (through CachedBuilder and robodiff-worker processes, so that another
//                 process warming the same key is waited for, not duplicated).
//   Interpreted - the interpreter over the freshly built graph: no compiler, ready at
//                 once (slower per knot; the right choice for one-off small jobs and tests).
// Either way the function is what the server and the client evaluate (same spec, same
// block layout), so a batch job's numbers equal a controller's.
//
// Thread-safe: evaluate/evaluateMany are const and keep their work buffers per call
// (evaluateMany) or per thread (evaluate).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

enum class Backend { Compiled, Interpreted };
const char* toString(Backend backend);  // "compiled", "interpreted"
Backend parseBackend(const std::string& text);  // throws std::invalid_argument naming the text

struct BatchFunctionOptions {
  Backend backend = Backend::Compiled;
  std::filesystem::path cache_dir;          // Compiled; empty: cache::defaultCacheDir()
  std::string compiler;                     // Compiled; empty: $CC or cc
  std::filesystem::path worker_executable;  // Compiled; empty: robodiff-worker beside this program, then PATH
  unsigned threads = 0;                     // evaluateMany's threads; 0: all cores
  // Told what happens while a Compiled function is obtained: "cached", "building", "built".
  std::function<void(const std::string& what)> on_progress;
};

// One block of inputs or outputs, as laid out in a knot's concatenated doubles.
struct BlockLayout {
  std::string name;
  std::uint32_t rows = 0, cols = 0;  // inputs: size x 1
  bool sparse = false;               // CSR: `size` nonzeros, pattern in row_ptr / col_idx
  std::uint32_t size = 0;            // doubles per knot
  std::uint32_t offset = 0;          // in the knot's concatenated doubles
  std::vector<std::uint32_t> row_ptr, col_idx;
};

class BatchFunction {
 public:
  // Builds (or finds) the function. `urdf_text` must be the text `model` was loaded from
  // (the cache key and the workers use it). Throws SpecError, std::runtime_error (a build
  // that failed: the worker's message), codegen::LoadError.
  static BatchFunction open(const Model& model, const std::string& urdf_text, bool floating_base,
                            const FunctionSpec& spec, const BatchFunctionOptions& options = {});

  Backend backend() const;
  const std::vector<BlockLayout>& inputs() const;
  const std::vector<BlockLayout>& outputs() const;
  std::size_t inputCount() const;   // doubles per knot, all input blocks
  std::size_t outputCount() const;  // doubles per knot, all output blocks
  const BlockLayout& input(const std::string& name) const;   // throws std::out_of_range
  const BlockLayout& output(const std::string& name) const;  // by name: value, jacobian, hessian, ...

  // One knot: `in` the input blocks concatenated, `out` room for the output blocks.
  void evaluate(const double* in, double* out) const;
  // `knots` knots, knot k at in + k * inputCount() and out + k * outputCount(), split
  // over the threads in chunks that use the batched entry point. `cancelled` (optional)
  // is polled between chunks; returns the knots done (all unless cancelled).
  std::uint64_t evaluateMany(std::uint64_t knots, const double* in, double* out,
                             const std::function<bool()>& cancelled = {},
                             const std::function<void(std::uint64_t done)>& progress = {}) const;

  struct Impl;

 private:
  explicit BatchFunction(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<const Impl> impl_;
};

}  // namespace robodiff::batch
