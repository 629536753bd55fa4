#include "asm_fixtures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace robodiff::codegen::testing {

std::vector<detail::AsmTarget> hostTargets() {
  std::vector<detail::AsmTarget> targets;
  const auto host = detail::hostAsmTarget();
  if (!host) return targets;
  targets.push_back(detail::AsmTarget{16});
  if (host->xmm_registers == 32) targets.push_back(detail::AsmTarget{32});
  return targets;
}

CodegenOptions withoutPairs() {
  CodegenOptions options;
  options.lane_pairs = false;
  return options;
}

GeneratedLibrary assembly(const Graph& g, const std::vector<FunctionDefinition>& fs, const detail::AsmTarget& target,
                          const CodegenOptions& options) {
  std::optional<GeneratedLibrary> lib = detail::generateAssemblyLibrary(g, fs, options, target);
  if (!lib) throw std::runtime_error("no assembly for these functions");
  return *lib;
}

LoadedLibrary compiled(const GeneratedLibrary& lib, const TempDir& dir, const std::string& name) {
  return LoadedLibrary::open(compileLibrary(lib, dir / (name + ".so")).library);
}

bool closeScaled(double got, double want, double tolerance) {
  if (std::isnan(got) || std::isnan(want)) return std::isnan(got) && std::isnan(want);
  return std::abs(got - want) <= tolerance * std::max(1.0, std::abs(want));
}

void expectGraphValuesAt(const Graph& g, const FunctionDefinition& f, const CompiledFunction& fn,
                         const std::vector<std::vector<double>>& in, double tolerance, const std::string& what) {
  std::vector<double> work(fn.workSize() + 1);
  const auto expected = reference(g, f, in, 0);
  auto out = outputBuffers(f, 1);
  fn.evaluate(pointers(in, f).data(), pointers(out, f).data(), work.data());
  for (std::size_t b = 0; b < out.size(); ++b)
    for (std::size_t k = 0; k < out[b].size(); ++k)
      EXPECT_TRUE(closeScaled(out[b][k], expected[b][k], tolerance))
          << what << ", block " << b << ", element " << k << ": " << out[b][k] << " against " << expected[b][k];
}

}  // namespace robodiff::codegen::testing
