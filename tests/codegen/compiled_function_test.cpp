// Generated, compiled and loaded functions: their values against the interpreter and
// Graph::evaluate, the batched entry point against the single one, split libraries
// against unsplit ones, several threads at once. For gcc, and clang and tcc when they
// are installed (the compiler chosen as $CC would be).
#include <map>
#include <memory>
#include <thread>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;

// One graph holding several functions: random ones covering every op, and structured ones.
struct Functions {
  Graph graph;
  std::vector<FunctionDefinition> definitions;
  Functions() {
    for (std::uint32_t seed = 1; seed <= 4; ++seed)
      definitions.push_back(randomFunction(graph, "random" + std::to_string(seed), seed, 250));
    definitions.push_back(chainFunction(graph, "fk", 7));
    definitions.push_back(triangularFunction(graph, "tri", 6));
    // 300 sparse values: a block the batched chunk claims with a memset first.
    definitions.push_back(triangularFunction(graph, "tri_large", 24));
    // Mostly zeros: stored one by one (single knots, up to 256 zeros), else one memset.
    definitions.push_back(bandedFunction(graph, "banded", 15));
    definitions.push_back(bandedFunction(graph, "banded_large", 40));
  }
};

// Operations per part of the split variant: several parts per function.
constexpr std::uint32_t kSplit = 200;

struct Built {
  TempDir dir;
  std::map<std::string, GeneratedFunctionInfo> info;
  CompileReport report;
  std::unique_ptr<LoadedLibrary> library;
};

std::unique_ptr<Built> build(const Functions& fs, const CodegenOptions& codegen, const CompilerOptions& compiler) {
  auto b = std::make_unique<Built>();
  const GeneratedLibrary lib = generateLibrary(fs.graph, fs.definitions, codegen);
  for (const auto& i : lib.functions) b->info[i.name] = i;
  b->report = compileLibrary(lib, b->dir / "functions.so", compiler);
  b->library = std::make_unique<LoadedLibrary>(LoadedLibrary::open(b->report.library));
  return b;
}

struct Variant {
  std::string compiler;
  OptimizationLevel level;
  bool native;
  double tolerance;  // against the interpreter: 0 means bit for bit
};

void PrintTo(const Variant& v, std::ostream* os) { *os << v.compiler << (v.native ? " -march=native" : ""); }

// Compiled once per variant, shared by the tests of the suite.
class CompiledFunctionTest : public ::testing::TestWithParam<Variant> {
 protected:
  static Functions& functions() {
    static Functions fs;
    return fs;
  }
  static const Built& built(const Variant& v, std::uint32_t split_threshold = 0) {
    static std::map<std::string, std::unique_ptr<Built>> cache;
    const std::string key = v.compiler + (v.native ? "-native" : "") + "-" + std::to_string(split_threshold);
    auto& slot = cache[key];
    if (!slot) {
      CodegenOptions codegen;
      codegen.split_threshold = split_threshold;
      CompilerOptions compiler;
      compiler.compiler = v.compiler;
      compiler.optimization = v.level;
      compiler.native = v.native;
      slot = build(functions(), codegen, compiler);
    }
    return *slot;
  }
  void SetUp() override {
    if (!haveProgram(GetParam().compiler)) GTEST_SKIP() << GetParam().compiler << " is not installed";
  }
};

void expectClose(double got, double want, double tolerance, const std::string& what) {
  if (tolerance == 0.0) {
    if (!(std::isnan(got) && std::isnan(want))) {
      ASSERT_EQ(got, want) << what;
    }
  } else {
    ASSERT_TRUE(closeRelative(got, want, tolerance)) << what << ": " << got << " vs " << want;
  }
}

TEST_P(CompiledFunctionTest, MatchesTheInterpreterAndGraphEvaluate) {
  const Built& b = built(GetParam());
  const Functions& fs = functions();
  for (const FunctionDefinition& f : fs.definitions) {
    const CompiledFunction compiled = b.library->function(f.name);
    const Interpreter interpreter(fs.graph, f);
    std::vector<double> work(compiled.workSize() + 1), iwork(interpreter.workSize());
    const auto in = randomInputs(f, 5, 42);
    for (std::uint64_t k = 0; k < 5; ++k) {
      auto got = outputBuffers(f, 1), interpreted = outputBuffers(f, 1);
      compiled.evaluate(pointers(in, f, k).data(), pointers(got, f).data(), work.data());
      interpreter.evaluate(pointers(in, f, k).data(), pointers(interpreted, f).data(), iwork.data());
      const auto expected = reference(fs.graph, f, in, k);
      for (std::size_t blk = 0; blk < got.size(); ++blk)
        for (std::size_t i = 0; i < got[blk].size(); ++i) {
          const std::string what = f.name + "." + f.outputs[blk].name + "[" + std::to_string(i) + "]";
          ASSERT_TRUE(closeRelative(got[blk][i], expected[blk][i])) << what << ": " << got[blk][i] << " vs " << expected[blk][i];
          expectClose(got[blk][i], interpreted[blk][i], GetParam().tolerance, what);
        }
    }
  }
}

TEST_P(CompiledFunctionTest, BatchedEqualsSingleForEveryRemainder) {
  const Built& b = built(GetParam());
  const Functions& fs = functions();
  for (const FunctionDefinition& f : fs.definitions) {
    const CompiledFunction compiled = b.library->function(f.name);
    const std::uint64_t w = compiled.batchWidth();
    if (!GetParam().native && GetParam().compiler != "tcc") {
      EXPECT_EQ(w, 2u) << "x86-64 baseline: SSE2 lanes";
    }
    if (GetParam().compiler == "tcc") {
      EXPECT_EQ(w, 1u) << "no vector extensions: a plain loop";
    }
    std::vector<double> work(compiled.workSize() + 1), bwork(compiled.batchWorkSize());
    for (std::uint64_t n : {std::uint64_t{0}, std::uint64_t{1}, w - 1, w, 3 * w + 1}) {
      const auto in = randomInputs(f, n, 7 + static_cast<std::uint32_t>(n));
      auto batched = outputBuffers(f, n);
      for (auto& blk : batched) std::fill(blk.begin(), blk.end(), -12345.0);
      compiled.evaluateBatch(n, pointers(in, f).data(), pointers(batched, f).data(), bwork.data());
      for (std::uint64_t k = 0; k < n; ++k) {
        auto single = outputBuffers(f, 1);
        compiled.evaluate(pointers(in, f, k).data(), pointers(single, f).data(), work.data());
        for (std::size_t blk = 0; blk < single.size(); ++blk)
          for (std::size_t i = 0; i < single[blk].size(); ++i)
            expectClose(batched[blk][k * single[blk].size() + i], single[blk][i], GetParam().tolerance,
                        f.name + " n=" + std::to_string(n) + " knot " + std::to_string(k));
      }
    }
  }
}

TEST_P(CompiledFunctionTest, SplitIntoPartsGivesIdenticalResults) {
  const Built& whole = built(GetParam());
  const Built& split = built(GetParam(), kSplit);
  // Every part was compiled by its own command, then linked.
  std::size_t part_files = 0;  // a function in one part stays in library.c
  for (const auto& [name, info] : split.info) part_files += info.parts > 1 ? info.parts : 0;
  EXPECT_GE(part_files, 8u);
  EXPECT_EQ(split.report.commands.size(), 1 + part_files + 1);  // library.c, the parts, the link
  for (const FunctionDefinition& f : functions().definitions) {
    const CompiledFunction a = whole.library->function(f.name), b = split.library->function(f.name);
    if (split.info.at(f.name).parts > 1) {
      EXPECT_GT(b.workSize(), 0u) << f.name << ": values cross parts through the work buffer";
    }
    const std::uint64_t n = 2 * b.batchWidth() + 1;
    const auto in = randomInputs(f, n, 99);
    std::vector<double> wa(a.batchWorkSize() + a.workSize() + 1), wb(b.batchWorkSize() + b.workSize() + 1);
    auto ra = outputBuffers(f, n), rb = outputBuffers(f, n), sa = outputBuffers(f, 1), sb = outputBuffers(f, 1);
    a.evaluateBatch(n, pointers(in, f).data(), pointers(ra, f).data(), wa.data());
    b.evaluateBatch(n, pointers(in, f).data(), pointers(rb, f).data(), wb.data());
    a.evaluate(pointers(in, f).data(), pointers(sa, f).data(), wa.data());
    b.evaluate(pointers(in, f).data(), pointers(sb, f).data(), wb.data());
    // Bit for bit, except where -march=native lets the compiler contract a * b + c into
    // an FMA differently when values pass through memory between parts.
    for (std::size_t blk = 0; blk < ra.size(); ++blk) {
      for (std::size_t i = 0; i < ra[blk].size(); ++i)
        expectClose(rb[blk][i], ra[blk][i], GetParam().tolerance, f.name + " batched");
      for (std::size_t i = 0; i < sa[blk].size(); ++i)
        expectClose(sb[blk][i], sa[blk][i], GetParam().tolerance, f.name + " single");
    }
  }
}

TEST_P(CompiledFunctionTest, EvaluatesFromSeveralThreadsWithTheirOwnWorkBuffers) {
  const Built& b = built(GetParam(), kSplit);  // the split variant: its work buffer matters
  const Functions& fs = functions();
  const FunctionDefinition& f = fs.definitions.at(4);  // fk
  const CompiledFunction compiled = b.library->function(f.name);
  constexpr int kThreads = 4, kKnots = 16;
  const auto in = randomInputs(f, kKnots, 5);
  std::vector<std::vector<std::vector<double>>> expected;
  for (std::uint64_t k = 0; k < kKnots; ++k) expected.push_back(reference(fs.graph, f, in, k));
  std::vector<int> mismatches(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      std::vector<double> work(compiled.workSize()), bwork(compiled.batchWorkSize());
      auto out = outputBuffers(f, 1);
      auto batched = outputBuffers(f, kKnots);
      for (int round = 0; round < 200; ++round) {
        const std::uint64_t k = static_cast<std::uint64_t>(round * kThreads + t) % kKnots;
        compiled.evaluate(pointers(in, f, k).data(), pointers(out, f).data(), work.data());
        for (std::size_t blk = 0; blk < out.size(); ++blk)
          for (std::size_t i = 0; i < out[blk].size(); ++i)
            if (!closeRelative(out[blk][i], expected[k][blk][i])) ++mismatches[t];
        if (round % 20 == 0) {
          compiled.evaluateBatch(kKnots, pointers(in, f).data(), pointers(batched, f).data(), bwork.data());
          for (std::uint64_t kk = 0; kk < kKnots; ++kk)
            for (std::size_t blk = 0; blk < out.size(); ++blk)
              for (std::size_t i = 0; i < out[blk].size(); ++i)
                if (!closeRelative(batched[blk][kk * out[blk].size() + i], expected[kk][blk][i])) ++mismatches[t];
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(mismatches[t], 0) << "thread " << t;
}

INSTANTIATE_TEST_SUITE_P(Compilers, CompiledFunctionTest,
                         ::testing::Values(Variant{"gcc", OptimizationLevel::O1, false, 0.0},
                                           Variant{"clang", OptimizationLevel::O1, false, 0.0},
                                           Variant{"tcc", OptimizationLevel::O1, false, 0.0},
                                           // FMA contraction: close, not bit for bit.
                                           Variant{"gcc", OptimizationLevel::O2, true, 1e-12}),
                         [](const ::testing::TestParamInfo<Variant>& info) {
                           return info.param.compiler + (info.param.native ? "_native" : "");
                         });

}  // namespace
}  // namespace robodiff::codegen

namespace robodiff::codegen {
namespace {

using namespace testing;

TEST(CompiledFunction, EdgeCasesNoInputsEmptyBlocksConstantsOnly) {
  Graph g;
  // No inputs at all: constants only. Then empty blocks beside real ones.
  FunctionDefinition constants{"constants", {}, {OutputBlock::dense("c", 1, 3, {g.constant(1.5), g.zero(), g.constant(-2.0)})}};
  NodeId x = g.input(0);
  FunctionDefinition empties{"empties",
                             {{"none", 0}, {"x", 1}},
                             {OutputBlock::dense("nothing", 0, 3, {}), OutputBlock::sparse("sparse_empty", 2, 2, {0, 0, 0}, {}, {}),
                              OutputBlock::dense("y", 1, 1, {g.unary(Op::Exp, x)})}};
  TempDir dir;
  CompilerOptions options;
  options.compiler = "gcc";
  options.optimization = OptimizationLevel::O1;
  const CompileReport report = compileLibrary(generateLibrary(g, {constants, empties}), dir / "edge.so", options);
  EXPECT_EQ(report.diagnostics, "");
  LoadedLibrary lib = LoadedLibrary::open(report.library);

  const CompiledFunction c = lib.function("constants");
  std::vector<double> work(c.batchWorkSize() + 1);
  std::vector<double> out(3 * 5, 0.0);
  double* outs[] = {out.data()};
  c.evaluate(nullptr, outs, work.data());
  EXPECT_EQ(std::vector<double>(out.begin(), out.begin() + 3), (std::vector<double>{1.5, 0.0, -2.0}));
  c.evaluateBatch(5, nullptr, outs, work.data());
  for (int k = 0; k < 5; ++k) EXPECT_EQ(out[k * 3 + 2], -2.0);

  const CompiledFunction e = lib.function("empties");
  std::vector<double> xs{0.0, 1.0, 2.0};
  std::vector<double> ys(3, 0.0);
  std::vector<double> bwork(e.batchWorkSize() + 1);
  const double* ins[] = {nullptr, xs.data()};
  double* eouts[] = {nullptr, nullptr, ys.data()};
  e.evaluateBatch(3, ins, eouts, bwork.data());
  EXPECT_EQ(ys, (std::vector<double>{1.0, std::exp(1.0), std::exp(2.0)}));
}

}  // namespace
}  // namespace robodiff::codegen
