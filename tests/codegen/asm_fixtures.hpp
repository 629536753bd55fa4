// Helpers shared by the assembly back end's tests (asm_*_test.cpp).
#pragma once

#include <functional>
#include <random>
#include <string>
#include <vector>

#include "asm_emitter.hpp"
#include "codegen_fixtures.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::codegen::testing {

// The targets this host runs: 16 registers wherever the back end applies, 32 with AVX-512.
std::vector<detail::AsmTarget> hostTargets();

#define SKIP_WITHOUT_ASSEMBLY()                                                          \
  if (::robodiff::codegen::testing::hostTargets().empty())                               \
  GTEST_SKIP() << "the assembly back end needs x86-64 with AVX2 and FMA"

// Without lane pairs: functions C would compute in pairs (the fixtures' rotation
// entries, column by column) are assembled as scalars.
CodegenOptions withoutPairs();

// The functions as assembly with `options` (throws where the back end declines them).
GeneratedLibrary assembly(const Graph& g, const std::vector<FunctionDefinition>& fs, const detail::AsmTarget& target,
                          const CodegenOptions& options = withoutPairs());

LoadedLibrary compiled(const GeneratedLibrary& lib, const TempDir& dir, const std::string& name);

// Within `tolerance` relative to the value or 1, whichever is larger (values near zero
// come from cancellation); NaN where the other is NaN.
bool closeScaled(double got, double want, double tolerance);

// Every output of `fn` at `in` within `tolerance` (closeScaled) of the graph's own evaluation.
void expectGraphValuesAt(const Graph& g, const FunctionDefinition& f, const CompiledFunction& fn,
                         const std::vector<std::vector<double>>& in, double tolerance, const std::string& what);

// Random values of what the assembly prints, each bounded by v / (1 + |v|): every
// operation, negated operands, sin and cos of inputs and of computed values; their
// arguments mostly recent values (chains), sometimes old ones (long lives, spills).
class RandomValues {
 public:
  // `constant(x)` makes the constants; `input(rng)` the input a sine or cosine takes.
  RandomValues(Graph& g, std::uint32_t seed, std::vector<NodeId> start, std::function<NodeId(double)> constant,
               std::function<NodeId(std::mt19937&)> input);
  void grow(int operations);
  void kernelsOfInputsOnly() { computed_kernels_ = false; }  // sin and cos at the entry only
  NodeId pick();  // a recent value, sometimes an old one
  const std::vector<NodeId>& pool() const { return pool_; }
  std::mt19937& rng() { return rng_; }

 private:
  Graph& g_;
  std::mt19937 rng_;
  std::vector<NodeId> pool_;
  std::function<NodeId(double)> constant_;
  std::function<NodeId(std::mt19937&)> input_;
  bool computed_kernels_ = true;
};

// RandomValues starting from inputs 0 .. inputs-1 (one block), sines and cosines of
// those, the constants as they are.
RandomValues randomOverInputs(Graph& g, std::uint32_t seed, std::uint32_t inputs);

}  // namespace robodiff::codegen::testing
