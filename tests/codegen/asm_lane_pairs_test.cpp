// Lane pairs in the assembly (asm_program.hpp): a twin-limbed function's pairs computed
// by packed instructions compute what the graph computes, with 16 and 32 registers:
// pairs packed from constants, adjacent inputs, one value and two scalars; negated pair
// operands (signs of packed multiply-adds); lanes read back as scalars from registers
// and from spill slots; pairs live across a sin-cos region whose argument goes through
// libm; twin kernels at the entry in neighbouring lanes, their results read as pairs
// from the frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <regex>
#include <string>

#include "asm_entry_kernels.hpp"
#include "asm_fixtures.hpp"
#include "lane_pairs.hpp"
#include "lowering.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;

// One limb of twinLimbs: the same operations for either side (RandomValues seeded
// alike), its inputs 2k + side (the two limbs' inputs adjacent), its constants scaled by
// side, input 8 read by both.
std::vector<NodeId> randomLimb(Graph& g, std::uint32_t seed, int operations, std::uint32_t side) {
  std::vector<NodeId> start;
  for (std::uint32_t k = 0; k < 4; ++k) start.push_back(g.input(2 * k + side));
  start.push_back(g.input(8));
  const double scale = 1.0 + 0.5 * side;
  RandomValues values(
      g, seed, start, [&](double x) { return g.constant(x * scale); },
      [&](std::mt19937& rng) { return g.input(2 * static_cast<std::uint32_t>(rng() % 4) + side); });
  values.grow(operations);
  return values.pool();
}

// Two limbs of the same random shape: outputs each limb's value beside its twin's
// (lane 0 and lane 1 stored), and products of one limb's values and the other's
// (both lanes read as scalars).
FunctionDefinition twinLimbs(Graph& g, std::uint32_t seed, int operations) {
  const std::vector<NodeId> left = randomLimb(g, seed, operations, 0), right = randomLimb(g, seed, operations, 1);
  std::mt19937 rng(seed + 1000);
  std::vector<NodeId> values;
  for (int e = 0; e < 12; ++e) {
    const std::size_t i = left.size() - 1 - rng() % std::min<std::size_t>(left.size(), 40);
    values.push_back(left[i]);
    values.push_back(right[i]);
  }
  for (int e = 0; e < 4; ++e)
    values.push_back(g.binary(Op::Mul, left[left.size() - 1 - rng() % 30], right[right.size() - 1 - rng() % 30]));
  return FunctionDefinition{"twins" + std::to_string(seed), {{"x", 9}}, {OutputBlock::dense("y", 7, 4, values)}};
}

// Two planar chains of `joints` links, the left one's angles inputs 0..joints-1, the
// right one's joints..2 joints-1 (twins far apart in the inputs), their lengths apart:
// each link's end point and direction, left beside right. Sin-cos of inputs only: the
// kernels run at the entry.
FunctionDefinition twinChains(Graph& g, std::uint32_t joints) {
  std::vector<NodeId> values;
  std::vector<NodeId> c(2, g.one()), s(2, g.zero()), x(2, g.zero()), y(2, g.zero());
  auto mul = [&](NodeId a, NodeId b) { return g.binary(Op::Mul, a, b); };
  for (std::uint32_t j = 0; j < joints; ++j)
    for (std::uint32_t side = 0; side < 2; ++side) {
      const NodeId q = g.input(side * joints + j), cq = g.unary(Op::Cos, q), sq = g.unary(Op::Sin, q);
      const NodeId c2 = g.binary(Op::Sub, mul(c[side], cq), mul(s[side], sq));
      s[side] = g.binary(Op::Add, mul(s[side], cq), mul(c[side], sq));
      c[side] = c2;
      const NodeId length = g.constant(0.3 + 0.1 * j + 0.05 * side);
      x[side] = g.binary(Op::Add, x[side], mul(length, c[side]));
      y[side] = g.binary(Op::Add, y[side], mul(length, s[side]));
      values.insert(values.end(), {x[side], y[side], c[side]});
    }
  return FunctionDefinition{"chains", {{"q", 2 * joints}}, {OutputBlock::dense("p", 6 * joints, 1, values)}};
}

// Twin joints' kernels take neighbouring lanes, so that a pair of their sines (or
// cosines) is read from the frame as it is; the values are the graph's, every argument
// within the kernels' range or beyond it (libm, lane by lane, writing the frame).
TEST(AsmLanePairs, TwinKernelsAtTheEntryTakeNeighbouringLanes) {
  SKIP_WITHOUT_ASSEMBLY();
  constexpr std::uint32_t joints = 5;
  Graph g;
  const FunctionDefinition f = twinChains(g, joints);
  detail::FunctionPairing pairing = detail::pairingOf(g, f);
  ASSERT_FALSE(pairing.ready_first_sums) << "the chains are computed in lane pairs";
  detail::LoweringOptions lo;
  lo.lane_pairs = detail::LanePairMode::Emit;
  lo.sincos_lanes = false;
  lo.lane_pair_memo = &pairing.memo;
  const detail::LoweredFunction lowered = detail::lower(g, f, lo);
  const auto lanes = detail::entryKernelLanes(lowered.chunks.at(0));
  ASSERT_TRUE(lanes.has_value());
  ASSERT_EQ(lanes->size(), 2 * joints);
  for (std::uint32_t k = 0; k < joints; ++k) {
    const std::uint32_t a = (*lanes)[2 * k].index, b = (*lanes)[2 * k + 1].index;
    EXPECT_EQ(std::min(a, b), k) << "lanes " << 2 * k << " and " << 2 * k + 1;
    EXPECT_EQ(std::max(a, b), joints + k) << "lanes " << 2 * k << " and " << 2 * k + 1;
  }
  const double specials[] = {6.0e5, -1.0e300, std::numeric_limits<double>::infinity()};
  for (const detail::AsmTarget& target : hostTargets()) {
    const GeneratedLibrary lib = assembly(g, {f}, target, CodegenOptions{});
    EXPECT_GT(lib.functions[0].lane_pairs, 0u);
    TempDir dir;
    const LoadedLibrary loaded = compiled(lib, dir, "chains");
    for (std::uint32_t position = 0; position < 2 * joints; ++position)
      for (double special : specials) {
        auto in = randomInputs(f, 1, 3 + position);
        expectGraphValuesAt(g, f, loaded.function("chains"), in, 1e-13, "within the range");
        in[0][position] = special;
        expectGraphValuesAt(g, f, loaded.function("chains"), in, 1e-13,
                            "input " + std::to_string(position) + " = " + std::to_string(special));
      }
  }
}

TEST(AsmLanePairs, ATwinLimbedFunctionIsAssembledWithItsPairs) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition f = twoLimbsFunction(g);  // C computes its twins in lane pairs
    const GeneratedLibrary lib = assembly(g, {f}, target, CodegenOptions{});
    ASSERT_EQ(lib.sources[0].path, "library.s");
    EXPECT_GT(lib.functions[0].lane_pairs, 0u);
    EXPECT_NE(lib.sources[0].text.find("vdivpd\t"), std::string::npos) << "the limbs' divisions two at a time";
    expectCompiledAsTheGraph(g, f, lib, 1e-13);
  }
  // Through generateLibrary, as a single-knot library asking for assembly.
  Graph g;
  CodegenOptions options;
  options.batch_width = 1;
  options.assembly = true;
  EXPECT_EQ(generateLibrary(g, {twoLimbsFunction(g)}, options).sources[0].path, "library.s");
}

// Each seed's function, its inputs random and, at one point, an input beyond the
// kernel's range (libm's sincos called with pairs live); over the seeds, every way a
// pair is made and read back appears.
TEST(AsmLanePairs, RandomTwinLimbsComputeWhatTheGraphComputes) {
  SKIP_WITHOUT_ASSEMBLY();
  // Printed: one value in both lanes, lane 1 moved out, two scalars packed (lane 1 from
  // memory), a pair spilled, packed multiply-adds, two adjacent inputs read as a pair.
  const char* features[] = {"vmovddup\t", "vpermilpd\t$1, %xmm", "vmovhpd\t", "vmovapd\t%xmm", "vfmadd231pd\t%xmm",
                            "vfnmadd231pd\t", "pd\t(%rax), %xmm"};
  std::vector<bool> seen(std::size(features), false);
  for (const detail::AsmTarget& target : hostTargets())
    for (std::uint32_t seed : {1u, 2u, 3u, 5u, 7u, 9u, 14u, 16u, 18u, 21u}) {  // 333-3,322 operations
      Graph g;
      const FunctionDefinition f = twinLimbs(g, seed, 30 + 25 * static_cast<int>(seed));
      const GeneratedLibrary lib = assembly(g, {f}, target, CodegenOptions{});
      const std::string what = std::to_string(target.xmm_registers) + " registers, seed " + std::to_string(seed);
      EXPECT_GT(lib.functions[0].lane_pairs, 0u) << what;
      const std::string text = std::regex_replace(lib.sources[0].text, std::regex("\t-?[0-9]+\\(%rax\\)"), "\t(%rax)");
      for (std::size_t k = 0; k < std::size(features); ++k)
        seen[k] = seen[k] || text.find(features[k]) != std::string::npos;
      TempDir dir;
      const LoadedLibrary loaded = compiled(lib, dir, f.name);
      for (std::uint32_t point = 1; point <= 3; ++point) {
        auto in = randomInputs(f, 1, point);
        if (point == 3) in[0][seed % 8] = 3.0e6;
        expectGraphValuesAt(g, f, loaded.function(f.name), in, 1e-12, what + ", point " + std::to_string(point));
      }
    }
  for (std::size_t k = 0; k < std::size(features); ++k) EXPECT_TRUE(seen[k]) << "never printed: " << features[k];
}

}  // namespace
}  // namespace robodiff::codegen
