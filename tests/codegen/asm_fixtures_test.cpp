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

RandomValues::RandomValues(Graph& g, std::uint32_t seed, std::vector<NodeId> start,
                           std::function<NodeId(double)> constant, std::function<NodeId(std::mt19937&)> input)
    : g_(g), rng_(seed), pool_(std::move(start)), constant_(std::move(constant)), input_(std::move(input)) {}

NodeId RandomValues::pick() {
  const std::size_t n = pool_.size();
  const std::size_t back = rng_() % 4 == 0 ? rng_() % n : rng_() % std::min<std::size_t>(n, 6);
  return pool_[n - 1 - back];
}

void RandomValues::grow(int operations) {
  Graph& g = g_;
  auto neg = [&](NodeId x) { return g.unary(Op::Neg, x); };
  auto bin = [&](Op op, NodeId x, NodeId y) { return g.binary(op, x, y); };
  for (int k = 0; k < operations; ++k) {
    const NodeId a = pick(), b = pick();
    NodeId v;
    switch (rng_() % 10) {
      case 0: v = bin(Op::Add, a, neg(b)); break;
      case 1: v = bin(Op::Sub, bin(Op::Mul, a, b), constant_(0.25 * (k % 7))); break;
      case 2: v = bin(Op::Mul, neg(a), b); break;
      case 3: v = bin(Op::Div, a, bin(Op::Add, constant_(1.5), g.unary(Op::Abs, b))); break;
      case 4: v = g.unary(Op::Sqrt, bin(Op::Add, g.one(), bin(Op::Mul, a, a))); break;
      case 5: v = g.unary(Op::Sin, rng_() % 2 || !computed_kernels_ ? input_(rng_) : a); break;
      case 6: v = g.unary(Op::Cos, rng_() % 2 || !computed_kernels_ ? input_(rng_) : bin(Op::Add, a, b)); break;
      case 7: v = bin(Op::Add, bin(Op::Mul, a, b), bin(Op::Mul, pick(), neg(pick()))); break;
      case 8: v = neg(bin(Op::Mul, a, b)); break;
      default: v = bin(Op::Sub, constant_(-0.5), bin(Op::Mul, a, constant_(3.0))); break;
    }
    pool_.push_back(bin(Op::Div, v, bin(Op::Add, g.one(), g.unary(Op::Abs, v))));
  }
}

RandomValues randomOverInputs(Graph& g, std::uint32_t seed, std::uint32_t inputs) {
  std::vector<NodeId> start;
  for (std::uint32_t i = 0; i < inputs; ++i) start.push_back(g.input(i));
  return RandomValues(
      g, seed, start, [&g](double x) { return g.constant(x); },
      [&g, inputs](std::mt19937& rng) { return g.input(static_cast<std::uint32_t>(rng() % inputs)); });
}

}  // namespace robodiff::codegen::testing
