// The assembly's list schedule (asm_schedule.hpp): a latency-bound program's longest
// chain starts first, a program the pipes bound and one with sin-cos regions in its body
// keep their order, an output group is packed just before its store, and every reordered
// program computes each value after its operands: hand-made programs, a kinematic chain
// and random functions, whose assembled code computes what the graph computes.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "asm_fixtures.hpp"
#include "asm_program.hpp"
#include "asm_schedule.hpp"
#include "lowering.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using detail::AsmProgram;
using detail::kNoValue;
using detail::MCode;
using detail::MOp;

// Scalar programs by hand: inputs x0.. at their homes, each operation a new value.
class ProgramBuilder {
 public:
  explicit ProgramBuilder(std::uint32_t inputs) {
    for (std::uint32_t i = 0; i < inputs; ++i) {
      detail::ValueHome h;
      h.kind = detail::ValueHome::Kind::Input;
      h.index = i;
      p_.homes.push_back(h);
    }
  }
  std::uint32_t zero() {
    detail::ValueHome h;
    h.kind = detail::ValueHome::Kind::Constant;
    p_.homes.push_back(h);
    return static_cast<std::uint32_t>(p_.homes.size() - 1);
  }
  std::uint32_t op(MCode code, std::uint32_t a, std::uint32_t b = kNoValue, std::uint32_t c = kNoValue) {
    MOp m;
    m.code = code;
    m.src[0] = a;
    m.src[1] = b;
    m.src[2] = c;
    m.dst = static_cast<std::uint32_t>(p_.homes.size());
    p_.homes.emplace_back();
    p_.ops.push_back(m);
    return m.dst;
  }
  std::uint32_t wide(MCode code, std::uint32_t a, std::uint32_t b) {
    const std::uint32_t v = op(code, a, b);
    p_.wide.resize(p_.homes.size(), false);
    p_.wide[v] = true;
    return v;
  }
  void store(MCode code, std::uint32_t v, std::uint32_t index) {
    MOp m;
    m.code = code;
    m.src[0] = v;
    m.index = index;
    p_.ops.push_back(m);
  }
  AsmProgram program() {
    p_.wide.resize(p_.homes.size(), false);
    p_.pair.resize(p_.homes.size(), false);
    return p_;
  }

 private:
  AsmProgram p_;
};

std::string describe(const MOp& op) {
  std::ostringstream s;
  s << static_cast<int>(op.code) << ":" << op.dst << ":" << op.dst2 << ":" << op.src[0] << "," << op.src[1] << ","
    << op.src[2] << ":" << op.block << "." << op.index << ":" << op.imm << op.negate_product << op.negate_addend;
  return s.str();
}

// `after` holds `before`'s operations, each after the operations computing its operands.
void expectAReorderingOf(const AsmProgram& before, const AsmProgram& after) {
  std::vector<std::string> a, b;
  for (const MOp& op : before.ops) a.push_back(describe(op));
  for (const MOp& op : after.ops) b.push_back(describe(op));
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b) << "the same operations";
  std::vector<bool> computed(after.values(), true);
  for (const MOp& op : after.ops)
    for (std::uint32_t v : {op.dst, op.dst2})
      if (v != kNoValue) computed[v] = false;
  for (std::size_t i = 0; i < after.ops.size(); ++i) {
    for (std::uint32_t s : after.ops[i].src)
      EXPECT_TRUE(s == kNoValue || computed[s]) << "operation " << i << " reads value " << s << " before it is computed";
    for (std::uint32_t v : {after.ops[i].dst, after.ops[i].dst2})
      if (v != kNoValue) computed[v] = true;
  }
}

std::size_t positionOf(const AsmProgram& p, std::uint32_t value) {
  for (std::size_t i = 0; i < p.ops.size(); ++i)
    if (p.ops[i].dst == value) return i;
  return p.ops.size();
}

TEST(AsmSchedule, ALatencyBoundProgramStartsItsLongestChainFirst) {
  ProgramBuilder b(3);
  std::uint32_t last_product = kNoValue;
  for (std::uint32_t k = 0; k < 8; ++k) {  // short, independent
    last_product = b.op(MCode::Mul, 0, 1);
    b.store(MCode::Store, last_product, k);
  }
  const std::uint32_t first = b.op(MCode::Mul, 2, 2);
  std::uint32_t chain = first;
  for (int k = 0; k < 12; ++k) chain = b.op(MCode::Fma, chain, 2, 1);
  b.store(MCode::Store, chain, 8);
  const AsmProgram before = b.program();
  AsmProgram after = before;
  ASSERT_TRUE(detail::scheduleForLatency(after));
  expectAReorderingOf(before, after);
  EXPECT_EQ(positionOf(after, first), 0u) << "the chain's first operation, 17th in the program's order, comes first";
  // The independent products fill the pipes while the chain waits on its multiply-adds.
  EXPECT_LT(positionOf(after, last_product), positionOf(after, first + 2)) << "the last product before the chain's third step";
}

TEST(AsmSchedule, AProgramThePipesBoundKeepsItsOrder) {
  ProgramBuilder b(4);
  for (std::uint32_t k = 0; k < 60; ++k) {  // 60 multiplications (30 cycles of two pipes), chains of 6 cycles
    const std::uint32_t p = b.op(MCode::Mul, k % 4, (k + 1) % 4);
    b.store(MCode::Store, b.op(MCode::Add, p, k % 3), k);
  }
  const AsmProgram before = b.program();
  AsmProgram after = before;
  EXPECT_FALSE(detail::scheduleForLatency(after));
  for (std::size_t i = 0; i < before.ops.size(); ++i) EXPECT_EQ(describe(after.ops[i]), describe(before.ops[i]));
}

TEST(AsmSchedule, AnOutputGroupIsPackedJustBeforeItsStore) {
  ProgramBuilder b(2);
  const std::uint32_t x = b.op(MCode::Mul, 0, 1), y = b.op(MCode::Add, 0, 1);
  const std::uint32_t low = b.wide(MCode::Pack2, x, y);  // ready at once, packed late
  std::uint32_t chain = b.op(MCode::Mul, 0, 0);
  for (int k = 0; k < 40; ++k) chain = b.op(MCode::Fma, chain, 1, 0);  // beyond the window
  const std::uint32_t high = b.wide(MCode::Pack2, chain, x);
  b.store(MCode::Store4, b.wide(MCode::Pack4, low, high), 0);
  const AsmProgram before = b.program();
  AsmProgram after = before;
  ASSERT_TRUE(detail::scheduleForLatency(after));
  expectAReorderingOf(before, after);
  const std::size_t n = after.ops.size();
  ASSERT_GE(n, 4u);
  const MCode tail[] = {MCode::Pack2, MCode::Pack2, MCode::Pack4, MCode::Store4};
  for (std::size_t k = 0; k < 4; ++k)
    EXPECT_EQ(after.ops[n - 4 + k].code, tail[k]) << "the group's packing, then its store, last";
}

// A group of four cleared whole, then values stored into it: the zeros must stay first.
TEST(AsmSchedule, AGroupClearedWholeStaysBeforeTheValuesStoredIntoIt) {
  ProgramBuilder b(2);
  const std::uint32_t zero = b.zero();
  std::uint32_t chain = b.op(MCode::Mul, 0, 1);
  for (int k = 0; k < 10; ++k) chain = b.op(MCode::Fma, chain, 1, 0);
  b.store(MCode::Store4, zero, 0);  // elements 0..3
  b.store(MCode::Store, 1, 2);      // an input, ready at once
  b.store(MCode::Store, chain, 1);
  const AsmProgram before = b.program();
  AsmProgram after = before;
  ASSERT_TRUE(detail::scheduleForLatency(after));
  expectAReorderingOf(before, after);
  std::vector<std::uint32_t> stored;
  for (const MOp& op : after.ops)
    if (op.code == MCode::Store || op.code == MCode::Store4) stored.push_back(op.index);
  EXPECT_EQ(stored, (std::vector<std::uint32_t>{0, 2, 1})) << "the group's zeros, then the input, then the chain";
}

TEST(AsmSchedule, AProgramWithSinCosRegionsInItsBodyKeepsItsOrder) {
  ProgramBuilder b(1);
  std::uint32_t chain = b.op(MCode::Mul, 0, 0);
  for (int k = 0; k < 10; ++k) chain = b.op(MCode::Fma, chain, 0, 0);
  MOp begin;
  begin.code = MCode::KernelBegin;
  begin.src[0] = chain;
  AsmProgram before = b.program();
  before.ops.push_back(begin);
  AsmProgram after = before;
  EXPECT_FALSE(detail::scheduleForLatency(after));
}

// A function's program as the assembly back end builds it (without lane pairs).
AsmProgram programOf(const Graph& g, const FunctionDefinition& f) {
  detail::LoweringOptions lo;
  lo.split_threshold = 0;
  lo.sincos_lanes = false;
  const detail::LoweredFunction lowered = detail::lower(g, f, lo);
  std::optional<AsmProgram> p = detail::buildAsmProgram(lowered.chunks.at(0), f);
  if (!p) throw std::runtime_error("the back end declines " + f.name);
  return *p;
}

// Random chains of every operation the assembly prints, sin and cos of inputs only (at
// the entry), outputs of recent and old values and zeros among them (groups of four
// cleared whole, then their values stored).
FunctionDefinition randomChains(Graph& g, std::uint32_t seed, int operations) {
  RandomValues values = randomOverInputs(g, seed, 6);
  values.kernelsOfInputsOnly();
  values.grow(operations);
  std::vector<NodeId> out;
  for (std::uint32_t e = 0; e < 12; ++e) out.push_back(e % 3 == 1 ? g.zero() : values.pick());
  return FunctionDefinition{"chains" + std::to_string(seed), {{"x", 6}}, {OutputBlock::dense("y", 12, 1, out)}};
}

TEST(AsmSchedule, ReorderedFunctionsComputeWhatTheGraphComputes) {
  SKIP_WITHOUT_ASSEMBLY();
  for (std::uint32_t seed = 0; seed <= 8; ++seed) {
    Graph g;
    const FunctionDefinition f = seed == 0 ? chainFunction(g, "chain", 12) : randomChains(g, seed, 60 * seed);
    const AsmProgram before = programOf(g, f);
    AsmProgram after = before;
    ASSERT_TRUE(detail::scheduleForLatency(after)) << f.name << ": its chains bound it";
    expectAReorderingOf(before, after);
    std::size_t moved = 0;
    for (std::size_t i = 0; i < before.ops.size(); ++i) moved += describe(after.ops[i]) != describe(before.ops[i]);
    EXPECT_GT(moved, before.ops.size() / 10) << f.name;
    for (const detail::AsmTarget& target : hostTargets()) {
      TempDir dir;
      const LoadedLibrary lib = compiled(assembly(g, {f}, target), dir, f.name);
      for (std::uint32_t point = 1; point <= 3; ++point)
        expectGraphValuesAt(g, f, lib.function(f.name), randomInputs(f, 1, point), 1e-12,
                            f.name + ", " + std::to_string(target.xmm_registers) + " registers");
    }
  }
}

}  // namespace
}  // namespace robodiff::codegen
