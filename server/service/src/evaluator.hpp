#pragma once
// What evaluates a function: the interpreter (from the moment it is traced) or the
// compiled library (once built or found in the cache). Both follow abi.h's conventions
// (one pointer per block, a caller's work buffer, batched knots block after block) and
// carry the function's layout, so one atomic load gives evaluation everything it needs.
// Immutable once made; shared by evaluations in flight (shared_ptr), so swapping the
// interpreter for the library never pulls one from under a running evaluation.

#include <cstdint>
#include <memory>
#include <optional>

#include "robodiff/runtime/function_layout.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::server::detail {

using runtime::FunctionLayout;

class Evaluator {
 public:
  explicit Evaluator(FunctionLayout layout) : layout_(std::move(layout)) {}
  virtual ~Evaluator() = default;

  const FunctionLayout& layout() const { return layout_; }
  virtual bool compiled() const = 0;
  virtual std::size_t workSize() const = 0;       // doubles, for evaluate
  virtual std::size_t batchWorkSize() const = 0;  // doubles, for evaluateBatch
  virtual std::uint32_t batchWidth() const = 0;   // knots the batched entry point does together
  virtual void evaluate(const double* const* in, double* const* out, double* work) const = 0;
  virtual void evaluateBatch(std::uint64_t n, const double* const* in, double* const* out, double* work) const = 0;

 private:
  FunctionLayout layout_;
};

class InterpretedEvaluator final : public Evaluator {
 public:
  InterpretedEvaluator(FunctionLayout layout, codegen::Interpreter interpreter)
      : Evaluator(std::move(layout)), interpreter_(std::move(interpreter)) {}
  bool compiled() const override { return false; }
  std::size_t workSize() const override { return interpreter_.workSize(); }
  std::size_t batchWorkSize() const override { return interpreter_.workSize(); }
  std::uint32_t batchWidth() const override { return 1; }
  void evaluate(const double* const* in, double* const* out, double* work) const override {
    interpreter_.evaluate(in, out, work);
  }
  void evaluateBatch(std::uint64_t n, const double* const* in, double* const* out, double* work) const override {
    interpreter_.evaluateBatch(n, in, out, work);
  }

 private:
  codegen::Interpreter interpreter_;
};

class CompiledEvaluator final : public Evaluator {
 public:
  // Keeps `artifact` (its cache entry pinned: never evicted while loaded) and the library.
  CompiledEvaluator(FunctionLayout layout, cache::Artifact artifact, codegen::CompiledFunction function)
      : Evaluator(std::move(layout)), artifact_(std::move(artifact)), function_(std::move(function)) {}
  bool compiled() const override { return true; }
  std::size_t workSize() const override { return function_.workSize(); }
  std::size_t batchWorkSize() const override { return function_.batchWorkSize(); }
  std::uint32_t batchWidth() const override { return function_.batchWidth(); }
  void evaluate(const double* const* in, double* const* out, double* work) const override {
    function_.evaluate(in, out, work);
  }
  void evaluateBatch(std::uint64_t n, const double* const* in, double* const* out, double* work) const override {
    function_.evaluateBatch(n, in, out, work);
  }
  const cache::Artifact& artifact() const { return artifact_; }

 private:
  cache::Artifact artifact_;
  codegen::CompiledFunction function_;
};

// Loads the library of a cache artifact and checks its function against what the cache
// recorded (the C name, and the block sizes of the index row) and against the spec.
// Throws codegen::LoadError / std::invalid_argument saying what does not match.
std::shared_ptr<const CompiledEvaluator> loadCompiled(const cache::Artifact& artifact, const FunctionSpec& spec);

}  // namespace robodiff::server::detail
