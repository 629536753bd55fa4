// Lane pairs (core/codegen/src/lane_pairs.hpp): isomorphic operations of single-knot code
// computed two at a time in one 128-bit vector. Two "limbs" run the same recursion on
// their own inputs, as a robot's legs do; the generated code pairs them, computes what
// the graph computes, in one part or split over several (values crossing parts through
// the work buffer, a pair's lanes side by side), and a compiler without vector types
// compiles the same source without pairs. One limb alone gets no pairs. One function's
// lowerings choose its pairs once (LanePairMemo).
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "codegen_fixtures.hpp"
#include "lane_pairs.hpp"
#include "lowering.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using robodiff::testing::TempDir;

struct PairedBuild {
  GeneratedLibrary generated;
  LoadedLibrary library;
};

PairedBuild buildLimbs(const Graph& g, const FunctionDefinition& f, const TempDir& dir, const std::string& name,
            const CodegenOptions& codegen, const std::string& compiler = "") {
  CompilerOptions options;
  options.compiler = compiler;
  options.native = compiler.empty();
  GeneratedLibrary generated = generateLibrary(g, {f}, codegen);
  LoadedLibrary library = LoadedLibrary::open(compileLibrary(generated, dir / (name + ".so"), options).library);
  return {std::move(generated), std::move(library)};
}

std::string sourcesOf(const GeneratedLibrary& lib) {
  std::string text;
  for (const SourceFile& s : lib.sources) text += s.text;
  return text;
}

// Every output within 1e-13 (relative) of the graph's own evaluation, on a few inputs.
void expectTheGraphsValues(const Graph& g, const FunctionDefinition& f, const LoadedLibrary& library) {
  const CompiledFunction& fn = library.function(f.name);
  std::vector<double> work(fn.workSize() + 1);
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    const auto in = randomInputs(f, 1, seed);
    const auto expected = reference(g, f, in, 0);
    auto out = outputBuffers(f, 1);
    fn.evaluate(pointers(in, f).data(), pointers(out, f).data(), work.data());
    for (std::size_t i = 0; i < expected[0].size(); ++i)
      EXPECT_TRUE(closeRelative(out[0][i], expected[0][i], 1e-13)) << seed << " " << i << ": " << out[0][i] << " vs "
                                                                    << expected[0][i];
  }
}

TEST(LanePairs, TwoLimbsArePairedAndComputeWhatTheGraphComputes) {
  Graph g;
  const FunctionDefinition f = twoLimbsFunction(g);
  TempDir dir;
  const PairedBuild paired = buildLimbs(g, f, dir, "paired", {});
  const GeneratedFunctionInfo& info = paired.generated.functions.at(0);
  std::cout << info.lane_pairs << " pairs in " << info.operations << " operations\n";
  // Every operation of the two limbs has its twin: all of them in pairs.
  EXPECT_EQ(2 * info.lane_pairs, info.operations);
  EXPECT_NE(sourcesOf(paired.generated).find("rd_pair p"), std::string::npos);
  expectTheGraphsValues(g, f, paired.library);

  CodegenOptions off;
  off.lane_pairs = false;
  const PairedBuild plain = buildLimbs(g, f, dir, "plain", off);
  EXPECT_EQ(plain.generated.functions.at(0).lane_pairs, 0u);
  EXPECT_EQ(plain.generated.functions.at(0).operations, info.operations);
  EXPECT_EQ(sourcesOf(plain.generated).find("rd_pair p"), std::string::npos);
  expectTheGraphsValues(g, f, plain.library);
}

TEST(LanePairs, SplitIntoPartsPairsStayWithinAPartAndValuesCrossThroughTheWorkBuffer) {
  Graph g;
  const FunctionDefinition f = twoLimbsFunction(g);
  CodegenOptions split;
  split.split_threshold = 30;
  TempDir dir;
  const PairedBuild built = buildLimbs(g, f, dir, "split", split);
  const GeneratedFunctionInfo& info = built.generated.functions.at(0);
  EXPECT_GE(info.parts, 4u);
  EXPECT_GT(info.transfer_slots, 0u);
  EXPECT_GT(2 * info.lane_pairs, info.operations / 2);
  // A pair's lanes handed to a later part side by side, and loaded there as a pair.
  EXPECT_NE(sourcesOf(built.generated).find("rd_store_pair(w + "), std::string::npos);
  EXPECT_NE(sourcesOf(built.generated).find("= rd_load_pair(w + "), std::string::npos);
  expectTheGraphsValues(g, f, built.library);
}

TEST(LanePairs, ACompilerWithoutVectorTypesCompilesTheSameSourceWithoutPairs) {
  if (!haveProgram("tcc")) GTEST_SKIP() << "tcc is not installed";
  Graph g;
  const FunctionDefinition f = twoLimbsFunction(g);
  TempDir dir;
  const PairedBuild built = buildLimbs(g, f, dir, "tcc", {}, "tcc");
  EXPECT_GT(built.generated.functions.at(0).lane_pairs, 0u);
  expectTheGraphsValues(g, f, built.library);
}

// A step below the recursions, x_next = x + 0.01 e, on every output: every output then
// matches every other to the depth the seeds look (an add of an input and a product with
// a constant, of a sum, ...), and only how deep they match tells the twins, a left link
// and the same right link, from two links of one limb. Both limbs' values in one block,
// the left limb's first, so that most candidate seeds are pairs of one limb's links; the
// right limb skewed a level deeper, so that pairs at one depth alone miss the twins.
TEST(LanePairs, TwinsAreToldApartBelowAStepCommonToEveryOutput) {
  Graph g;
  constexpr std::uint32_t inputs = 2 + 2 * kLimbLinks;
  std::vector<NodeId> values = limbValues(g, 0);
  const std::vector<NodeId> right = limbValues(g, inputs, true);
  values.insert(values.end(), right.begin(), right.end());
  for (std::uint32_t i = 0; i < values.size(); ++i)
    values[i] = g.binary(Op::Add, g.input(2 * inputs + i), g.binary(Op::Mul, g.constant(0.01), values[i]));
  const FunctionDefinition f{"stepped", {{"x", 2 * inputs + 2 * kLimbLinks}},
                             {OutputBlock::dense("x_next", 2 * kLimbLinks, 1, values)}};
  TempDir dir;
  const PairedBuild built = buildLimbs(g, f, dir, "stepped", {});
  const GeneratedFunctionInfo& info = built.generated.functions.at(0);
  std::cout << info.lane_pairs << " pairs in " << info.operations << " operations\n";
  EXPECT_EQ(2 * info.lane_pairs, info.operations - 1);  // all but the skew
  expectTheGraphsValues(g, f, built.library);
}

// A Jacobian's twins sit in different columns: d e_left / d x_left and d e_right /
// d x_right. Here the limbs' values are the two columns of one block; seeded at twins only
// (as derivative functions are), every operation still finds its twin.
TEST(LanePairs, TwinsInDifferentColumnsArePairedWhenSeededAtTwinsOnly) {
  Graph g;
  FunctionDefinition f = twoLimbsFunction(g, 2);
  f.lane_pairs = LanePairSeeds::Twins;
  TempDir dir;
  const PairedBuild built = buildLimbs(g, f, dir, "columns", {});
  const GeneratedFunctionInfo& info = built.generated.functions.at(0);
  std::cout << info.lane_pairs << " pairs in " << info.operations << " operations\n";
  // All but a few next to the inputs, which would cost more insertions than they save.
  EXPECT_GE(2 * info.lane_pairs, info.operations * 9 / 10);
  expectTheGraphsValues(g, f, built.library);

  f.lane_pairs = LanePairSeeds::None;
  EXPECT_EQ(generateLibrary(g, {f}).functions.at(0).lane_pairs, 0u);
}

// Calls of the pair or quad kernel `name` on pair locals, in the body (p3) or at its
// entry (rd_x0): the definitions in the prologue take other names.
std::size_t kernelCalls(const std::string& text, const std::string& name) {
  return countOf(text, name + "(p") + countOf(text, name + "(rd_x");
}

// Sin and cos of three joint angles (inputs): one 256-bit kernel call, its fourth lane
// repeating the third angle (kernels without checks of their own: the function checks
// the angles at entry); every value as libm computes it (within 2 ulp), also where one
// angle is beyond the kernel's range.
TEST(LanePairs, SinAndCosOfThreeAnglesRunInOneQuadCall) {
  Graph g;
  std::vector<NodeId> values;
  for (std::uint32_t j = 0; j < 3; ++j) {
    const NodeId q = g.input(j);
    values.push_back(g.unary(Op::Sin, q));
    values.push_back(g.unary(Op::Cos, q));
  }
  const FunctionDefinition f{"angles", {{"q", 3}}, {OutputBlock::dense("sc", 6, 1, values)}};
  TempDir dir;
  const PairedBuild built = buildLimbs(g, f, dir, "angles", {});
  const std::string source = sourcesOf(built.generated);
  EXPECT_EQ(kernelCalls(source, "rd_sincos_quad_in_range"), 1u) << "one call for three angles:\n" << source;
  EXPECT_EQ(kernelCalls(source, "rd_sincos_pair_in_range"), 0u) << source;
  EXPECT_EQ(source.find("  rd_sincos1_in_range("), std::string::npos) << source;
  const CompiledFunction& fn = built.library.function("angles");
  using Angles = std::array<double, 3>;
  for (const Angles& q : {Angles{0.3, -2.5, 7.0}, Angles{1e6, 0.5, -1e7}, Angles{-0.0, 1e-300, 3.0}}) {
    std::vector<double> out(6), work(fn.workSize() + 1);
    const double* in[] = {q.data()};
    double* outs[] = {out.data()};
    fn.evaluate(in, outs, work.data());
    for (std::uint32_t j = 0; j < 3; ++j) {
      EXPECT_TRUE(closeRelative(out[2 * j], std::sin(q[j]), 1e-15)) << q[j] << ": " << out[2 * j];
      EXPECT_TRUE(closeRelative(out[2 * j + 1], std::cos(q[j]), 1e-15)) << q[j] << ": " << out[2 * j + 1];
    }
  }
}

struct KernelCalls {
  std::uint32_t angles;
  std::size_t quads, pairs, singles;
};

// Angles in groups of four: a 256-bit kernel call for four (or three), a pair for two,
// the scalar kernel for one; the same bits as the build without lane pairs (the scalar
// kernel), with angles beyond the kernel's range among them (libm for them).
class SinCosGroups : public ::testing::TestWithParam<KernelCalls> {};

TEST_P(SinCosGroups, SameBitsAsTheScalarKernel) {
  const std::uint32_t n = GetParam().angles;
  Graph g;
  std::vector<NodeId> values;
  for (std::uint32_t j = 0; j < n; ++j) {
    const NodeId q = g.input(j);
    values.push_back(g.unary(Op::Sin, q));
    values.push_back(g.unary(Op::Cos, q));
  }
  const FunctionDefinition f{"angles", {{"q", n}}, {OutputBlock::dense("sc", 2 * n, 1, values)}};
  TempDir dir;
  const PairedBuild quad = buildLimbs(g, f, dir, "quad", {});
  const std::string all = sourcesOf(quad.generated);
  const std::size_t paired = all.find("#if RD_PAIRS\nRD_SCALAR_FN");  // the paired single-knot code
  ASSERT_NE(paired, std::string::npos) << all;
  const std::string source = all.substr(paired, all.find("#else", paired) - paired);
  EXPECT_EQ(kernelCalls(source, "rd_sincos_quad_in_range"), GetParam().quads) << source;
  EXPECT_EQ(kernelCalls(source, "rd_sincos_pair_in_range"), GetParam().pairs) << source;
  EXPECT_EQ(countOf(source, "  rd_sincos1_in_range("), GetParam().singles) << source;
  CodegenOptions off;
  off.lane_pairs = false;
  const PairedBuild plain = buildLimbs(g, f, dir, "plain", off);
  EXPECT_EQ(sourcesOf(plain.generated).find("rd_sincos_quad(p"), std::string::npos);
  const std::vector<std::vector<double>> states = {{0.3, -2.5, 7.0, 1.25, -0.75, 100.0, 2.0},
                                                   {1e6, 0.5, -1e7, 3.0, 0.1, 0.2, 0.3},
                                                   {-0.0, 1e-300, 3.0, 0x1p19, -1.5, 1e9, 0.4},
                                                   {0.1, 0.2, 0.3, 0.4, 0.5, 0x1p19, -1e300}};
  for (const std::vector<double>& q : states) {
    std::vector<double> got(2 * n), want(2 * n), work(4096);
    const double* in[] = {q.data()};
    double* outs[] = {got.data()};
    quad.library.function("angles").evaluate(in, outs, work.data());
    outs[0] = want.data();
    plain.library.function("angles").evaluate(in, outs, work.data());
    for (std::uint32_t k = 0; k < 2 * n; ++k) {
      EXPECT_EQ(got[k], want[k]) << "angle " << q[k / 2] << (k % 2 ? " cos" : " sin");
      const double exact = k % 2 ? std::cos(q[k / 2]) : std::sin(q[k / 2]);
      EXPECT_TRUE(closeRelative(got[k], exact, 1e-15) || std::fabs(got[k] - exact) < 1e-300) << q[k / 2];
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Angles, SinCosGroups,
                         ::testing::Values(KernelCalls{5, 1, 0, 1}, KernelCalls{6, 1, 1, 0}, KernelCalls{7, 2, 0, 0}),
                         [](const auto& info) { return std::to_string(info.param.angles) + "_angles"; });

// What the function builder compares two ways of building by: the single-knot
// instructions, one per operation less one per lane pair, as the library lowers it.
TEST(LanePairs, SingleKnotInstructionsCountAPairOnce) {
  Graph g;
  const FunctionDefinition f = twoLimbsFunction(g);
  const GeneratedFunctionInfo info = generateLibrary(g, {f}).functions.at(0);
  ASSERT_GT(info.lane_pairs, 0u);
  EXPECT_EQ(singleKnotInstructions(g, f, {}), info.operations - info.lane_pairs);
  EXPECT_EQ(singleKnotInstructions(g, f, {}), info.operations / 2);  // every operation has its twin
  CodegenOptions off;
  off.lane_pairs = false;
  EXPECT_EQ(singleKnotInstructions(g, f, off), info.operations);
}

TEST(LanePairs, OneLimbHasNoTwinAndNoPairs) {
  Graph g;
  const std::vector<NodeId> values = limbValues(g, 0);
  const FunctionDefinition f{"limb", {{"x", 2 + 2 * kLimbLinks}}, {OutputBlock::dense("e", kLimbLinks, 1, values)}};
  const GeneratedLibrary lib = generateLibrary(g, {f});
  EXPECT_EQ(lib.functions.at(0).lane_pairs, 0u);
  EXPECT_EQ(sourcesOf(lib).find("rd_pair p"), std::string::npos);
}

// What a lowering computes, instruction by instruction (kinds, operations, slots, operands).
std::string loweredText(const detail::LoweredFunction& l) {
  std::string text;
  for (const detail::Chunk& c : l.chunks)
    for (const detail::Instr& i : c.code) {
      text += std::to_string(static_cast<int>(i.kind)) + ":" + std::to_string(static_cast<int>(i.op)) + ":" +
              std::to_string(i.dst) + ":" + std::to_string(i.index);
      for (const detail::Operand& a : i.args)
        text += "," + std::to_string(static_cast<int>(a.kind)) + ":" + std::to_string(a.slot) + ":" +
                std::to_string(a.lane) + ":" + std::to_string(a.value);
      text += ";";
    }
  return text;
}

// The lowering that fills a memo and the one that reuses it lower as one without it; a
// memo filled from sums chained otherwise, or by another function's steps, is not taken.
TEST(LanePairs, OneFunctionsLoweringsShareItsPairsThroughAMemo) {
  Graph g;
  const FunctionDefinition limbs = twoLimbsFunction(g);
  const std::vector<NodeId> one = limbValues(g, 0);
  const FunctionDefinition limb{"limb", {{"x", 2 + 2 * kLimbLinks}}, {OutputBlock::dense("e", kLimbLinks, 1, one)}};
  detail::LoweringOptions options;
  options.lane_pairs = detail::LanePairMode::Emit;
  const detail::LoweredFunction alone = detail::lower(g, limbs, options);
  ASSERT_GT(alone.lane_pairs, 0u);

  detail::LanePairMemo memo;
  options.lane_pair_memo = &memo;
  const detail::LoweredFunction filling = detail::lower(g, limbs, options);
  EXPECT_TRUE(memo.filled);
  const std::vector<detail::Step> filled_with = memo.steps_in;
  const detail::LoweredFunction reusing = detail::lower(g, limbs, options);
  EXPECT_EQ(memo.steps_in, filled_with);
  EXPECT_EQ(loweredText(filling), loweredText(alone));
  EXPECT_EQ(loweredText(reusing), loweredText(alone));

  // Sums chained in order of readiness make another graph: paired afresh.
  options.ready_first_sums = true;
  options.lane_pair_memo = nullptr;
  const detail::LoweredFunction ready_first_alone = detail::lower(g, limbs, options);
  options.lane_pair_memo = &memo;
  EXPECT_EQ(loweredText(detail::lower(g, limbs, options)), loweredText(ready_first_alone));
  EXPECT_TRUE(memo.ready_first_sums);
  options.ready_first_sums = false;

  options.lane_pair_memo = nullptr;
  const detail::LoweredFunction limb_alone = detail::lower(g, limb, options);
  options.lane_pair_memo = &memo;
  EXPECT_EQ(loweredText(detail::lower(g, limb, options)), loweredText(limb_alone));
  EXPECT_NE(memo.steps_in, filled_with);  // refilled with the other function's steps
}

}  // namespace
}  // namespace robodiff::codegen
