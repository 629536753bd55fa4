// The assembly back end (core/codegen/src/asm_*.hpp): single-knot libraries written as
// x86-64 assembly compute what the graph computes, with 16 registers (AVX2) and with 32
// (AVX-512); sin-cos kernels at the entry and in the body, their arguments beyond the
// kernel's range through libm; spills under register pressure; the descriptor tables
// and the batch loop; and what stays C.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "asm_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using robodiff::testing::TempDir;

// sin and cos of sums and products of the inputs (no kernel takes an input as it is: the
// kernels run in the body), through long chains of products; n > 2.
FunctionDefinition computedAngles(Graph& g, std::uint32_t n) {
  std::vector<NodeId> values;
  NodeId carried = g.one();
  for (std::uint32_t j = 0; j < n; ++j) {
    const NodeId angle = g.binary(Op::Add, g.input(j), g.binary(Op::Mul, g.input((j + 1) % n), g.constant(0.5)));
    const NodeId s = g.unary(Op::Sin, angle), c = g.unary(Op::Cos, angle);
    carried = g.binary(Op::Sub, g.binary(Op::Mul, carried, c), g.binary(Op::Mul, s, g.input(j)));
    values.push_back(carried);
    values.push_back(g.binary(Op::Div, s, g.binary(Op::Add, g.constant(2.0), c)));
  }
  // A lone sin and a lone cos: the kernel's other result unused.
  values.push_back(g.unary(Op::Sin, g.binary(Op::Mul, g.input(0), g.input(1))));
  values.push_back(g.unary(Op::Cos, g.binary(Op::Sub, g.input(1), g.input(2))));
  return FunctionDefinition{"computed", {{"x", n}}, {OutputBlock::dense("y", 2 * n + 2, 1, values)}};
}

// Every operation the back end prints, each operand sign in each position, constants on
// either side, outputs copied from inputs (negated too), constants and zeros.
FunctionDefinition everySign(Graph& g) {
  const NodeId a = g.input(0), b = g.input(1), c = g.input(2), na = g.unary(Op::Neg, a), nb = g.unary(Op::Neg, b);
  auto bin = [&](Op op, NodeId x, NodeId y) { return g.binary(op, x, y); };
  std::vector<NodeId> v;
  for (Op op : {Op::Add, Op::Sub, Op::Mul, Op::Div})
    for (NodeId x : {a, na, g.constant(1.5)})
      for (NodeId y : {b, nb, g.constant(-0.75)}) v.push_back(bin(op, x, y));
  // Products read once by a sum (fused), with every sign of factors and addend.
  for (NodeId x : {a, na})
    for (NodeId y : {b, nb})
      for (NodeId z : {c, g.unary(Op::Neg, c)}) {
        v.push_back(bin(Op::Add, bin(Op::Mul, x, y), z));
        v.push_back(bin(Op::Sub, z, bin(Op::Mul, x, y)));
        v.push_back(bin(Op::Sub, bin(Op::Mul, x, y), z));
      }
  v.push_back(g.unary(Op::Sqrt, bin(Op::Add, g.constant(2.0), bin(Op::Mul, a, a))));
  v.push_back(g.unary(Op::Sqrt, g.unary(Op::Neg, bin(Op::Sub, g.constant(-3.0), b))));
  v.push_back(g.unary(Op::Abs, na));
  v.push_back(g.unary(Op::Neg, bin(Op::Mul, a, b)));
  v.push_back(g.unary(Op::Neg, g.unary(Op::Neg, c)));
  v.push_back(a);
  v.push_back(nb);
  v.push_back(g.constant(0.25));
  v.push_back(g.zero());
  v.push_back(g.constant(-0.0));
  const auto n = static_cast<std::uint32_t>(v.size());
  return FunctionDefinition{"signs", {{"x", 3}}, {OutputBlock::dense("y", n, 1, v)}};
}

// `n` values live at once: products of the inputs, each read again only at the end, in
// the reverse order (more than any register file holds).
FunctionDefinition manyLiveValues(Graph& g, std::uint32_t n) {
  std::vector<NodeId> products;
  for (std::uint32_t i = 0; i < n; ++i)
    products.push_back(g.binary(Op::Mul, g.input(i % 5), g.binary(Op::Add, g.input((i + 1) % 5), g.constant(i + 1.0))));
  NodeId sum = g.zero();
  std::vector<NodeId> outputs;
  for (std::uint32_t i = n; i-- > 0;) {
    sum = g.binary(Op::Add, g.binary(Op::Mul, sum, g.constant(0.5)), products[i]);
    if (i % 16 == 0) outputs.push_back(sum);
  }
  const auto m = static_cast<std::uint32_t>(outputs.size());
  return FunctionDefinition{"pressure", {{"x", 5}}, {OutputBlock::dense("y", m, 1, outputs)}};
}

TEST(AsmBackend, AKinematicChainComputesWhatTheGraphComputes) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition f = chainFunction(g, "chain", 7);
    const GeneratedLibrary lib = assembly(g, {f}, target);
    ASSERT_EQ(lib.sources.size(), 1u);
    EXPECT_EQ(lib.sources[0].path, "library.s");
    EXPECT_NE(lib.sources[0].text.find("vfmadd231pd"), std::string::npos) << "the kernels at entry, in vectors";
    expectCompiledAsTheGraph(g, f, lib, 1e-13);
  }
}

TEST(AsmBackend, EveryOperationAndSignComputesWhatTheGraphComputes) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition f = everySign(g);
    TempDir dir;
    const LoadedLibrary lib = compiled(assembly(g, {f}, target), dir, "signs");
    for (std::uint32_t seed = 1; seed <= 4; ++seed)
      expectGraphValuesAt(g, f, lib.function("signs"), randomInputs(f, 1, seed), 1e-15,
                          std::to_string(target.xmm_registers) + " registers, seed " + std::to_string(seed));
  }
}

TEST(AsmBackend, SparseBandedAndTriangularOutputsAreWrittenWhole) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition banded = bandedFunction(g, "banded", 11), triangular = triangularFunction(g, "tri", 9);
    const GeneratedLibrary lib = assembly(g, {banded, triangular}, target);
    expectCompiledAsTheGraph(g, banded, lib, 1e-14);  // outputs start NaN: an unwritten zero fails
    expectCompiledAsTheGraph(g, triangular, lib, 1e-14);
  }
}

// A frame-Jacobian-like block: few operations, many stores, values scattered among
// zeros (groups of one to four values, runs of zeros between them).
FunctionDefinition storeBound(Graph& g) {
  std::vector<NodeId> values;
  for (std::uint32_t e = 0; e < 90; ++e) {
    const std::uint32_t pattern = (e * 7) % 11;
    if (pattern < 4) values.push_back(g.binary(Op::Mul, g.input(e % 6), g.constant(1.0 + e)));
    else if (pattern == 4) values.push_back(g.unary(Op::Neg, g.input(e % 6)));
    else values.push_back(g.zero());
  }
  return FunctionDefinition{"scattered", {{"x", 6}}, {OutputBlock::dense("J", 6, 15, values)}};
}

TEST(AsmBackend, StoreBoundOutputsAreWrittenFourAtATime) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition f = storeBound(g);
    const GeneratedLibrary lib = assembly(g, {f}, target);
    const std::string& text = lib.sources[0].text;
    EXPECT_NE(text.find("vunpcklpd"), std::string::npos) << "two values in one register";
    EXPECT_NE(text.find("vmovq"), std::string::npos) << "a value and zeros";
    EXPECT_NE(text.find(target.xmm_registers > 16 ? "vinsertf32x4" : "vinsertf128"), std::string::npos);
    EXPECT_NE(text.find("vzeroupper\n\tret"), std::string::npos) << "256-bit registers written";
    expectCompiledAsTheGraph(g, f, lib, 1e-15);  // outputs start NaN: an unwritten element fails
  }
}

TEST(AsmBackend, KernelsOfComputedArgumentsRunInTheBody) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition f = computedAngles(g, 9);
    const GeneratedLibrary lib = assembly(g, {f}, target);
    EXPECT_EQ(lib.sources[0].text.find("vfmadd231pd"), std::string::npos) << "no kernel at entry";
    EXPECT_NE(lib.sources[0].text.find("call\tsincos@PLT"), std::string::npos) << "libm beyond the range";
    expectCompiledAsTheGraph(g, f, lib, 1e-13);
  }
}

// Arguments beyond 2^19, infinite or not a number go through libm's sincos: the values
// are the graph's (std::sin and std::cos), whichever kernel and lane they reach, and the
// other kernels' lanes are unaffected.
TEST(AsmBackend, ArgumentsBeyondTheKernelRangeGoThroughLibm) {
  SKIP_WITHOUT_ASSEMBLY();
  const double specials[] = {6.0e5, -3.0e7, 1.0e300, std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN()};
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition chain = chainFunction(g, "chain", 7), computed = computedAngles(g, 7);
    TempDir dir;
    const LoadedLibrary lib = compiled(assembly(g, {chain, computed}, target), dir, "beyond");
    for (const FunctionDefinition* f : {&chain, &computed})
      for (std::uint32_t position = 0; position < 7; ++position)
        for (double x : specials) {
          auto in = randomInputs(*f, 1, 7 + position);
          in[0][position] = x;
          expectGraphValuesAt(g, *f, lib.function(f->name), in, 1e-13,
                              f->name + ": input " + std::to_string(position) + " = " + std::to_string(x));
        }
  }
}

TEST(AsmBackend, ValuesBeyondTheRegistersAreSpilledAndReadBack) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition f = manyLiveValues(g, 120);
    const GeneratedLibrary lib = assembly(g, {f}, target);
    EXPECT_NE(lib.sources[0].text.find("(%rsp)\n"), std::string::npos) << "spill slots";
    EXPECT_EQ(lib.sources[0].text.find("(%rbp), %xmm"), std::string::npos) << "a small function: no frame base";
    expectCompiledAsTheGraph(g, f, lib, 1e-14);
  }
}

// A large function reads its frame through %rbp and its constants through %rbx
// (asm_addressing.hpp), several bytes apart in both: the values are still the graph's.
TEST(AsmBackend, ALargeFunctionReadsItsFrameAndConstantsThroughBaseRegisters) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets()) {
    Graph g;
    const FunctionDefinition f = manyLiveValues(g, 1200);
    const GeneratedLibrary lib = assembly(g, {f}, target);
    const std::string& text = lib.sources[0].text;
    EXPECT_NE(text.find("\tpush\t%rbp\n\tpush\t%rbx\n"), std::string::npos);
    EXPECT_NE(text.find("(%rbp), %xmm"), std::string::npos) << "spilled values read back";
    EXPECT_NE(text.find("(%rbx), %xmm"), std::string::npos) << "constants";
    EXPECT_NE(text.find("\tpop\t%rbx\n\tpop\t%rbp\n"), std::string::npos);
    expectCompiledAsTheGraph(g, f, lib, 1e-13);
  }
}

// A random function of what the assembly prints (RandomValues): sin and cos of inputs
// (at entry) and of computed values (in the body). Two input blocks; a dense block with
// zeros and a sparse one.
FunctionDefinition randomPrinted(Graph& g, std::uint32_t seed, int operations) {
  RandomValues values = randomOverInputs(g, seed, 8);
  values.grow(operations);
  auto pick = [&] { return values.pick(); };
  std::mt19937& rng = values.rng();
  const std::vector<NodeId>& pool = values.pool();
  std::vector<NodeId> dense;
  for (std::uint32_t e = 0; e < 24; ++e) dense.push_back(e % 5 == 3 ? g.zero() : pick());
  std::vector<std::uint32_t> row_ptr{0, 2, 2, 5}, col_idx{0, 3, 1, 2, 4};
  std::vector<NodeId> sparse;
  for (std::uint32_t e = 0; e < 5; ++e) sparse.push_back(pool[rng() % pool.size()]);
  return FunctionDefinition{"random" + std::to_string(seed),
                            {{"x", 5}, {"y", 3}},
                            {OutputBlock::dense("d", 6, 4, dense), OutputBlock::sparse("s", 3, 5, row_ptr, col_idx, sparse)}};
}

TEST(AsmBackend, RandomFunctionsComputeWhatTheGraphComputes) {
  SKIP_WITHOUT_ASSEMBLY();
  for (const detail::AsmTarget& target : hostTargets())
    for (std::uint32_t seed = 1; seed <= 12; ++seed) {
      Graph g;
      const FunctionDefinition f = randomPrinted(g, seed, 40 + 50 * static_cast<int>(seed));
      TempDir dir;
      const LoadedLibrary lib = compiled(assembly(g, {f}, target), dir, f.name);
      const std::string what = std::to_string(target.xmm_registers) + " registers, seed " + std::to_string(seed);
      for (std::uint32_t point = 1; point <= 3; ++point) {
        auto in = randomInputs(f, 1, point);
        if (point == 3) in[0][seed % 5] = 3.0e6;  // a kernel's argument beyond its range
        expectGraphValuesAt(g, f, lib.function(f.name), in, 1e-12, what + ", point " + std::to_string(point));
      }
    }
}

// The descriptor tables say what the definitions say, and eval_batch is eval knot by knot.
TEST(AsmBackend, TheLibraryDescribesItsFunctionsAndItsBatchLoopEvaluatesEachKnot) {
  SKIP_WITHOUT_ASSEMBLY();
  Graph g;
  const FunctionDefinition chain = chainFunction(g, "chain", 5), tri = triangularFunction(g, "tri", 6);
  TempDir dir;
  const LoadedLibrary lib = compiled(assembly(g, {chain, tri}, hostTargets().back()), dir, "two");
  EXPECT_EQ(lib.generatorVersion(), kGeneratorVersion);
  for (const FunctionDefinition* f : {&chain, &tri}) {
    const CompiledFunction fn = lib.function(f->name);
    const robodiff_function_desc& d = fn.descriptor();
    ASSERT_EQ(d.n_inputs, f->inputs.size());
    for (std::size_t b = 0; b < f->inputs.size(); ++b) {
      EXPECT_EQ(std::string(d.inputs[b].name), f->inputs[b].name);
      EXPECT_EQ(d.inputs[b].size, f->inputs[b].size);
    }
    ASSERT_EQ(d.n_outputs, f->outputs.size());
    for (std::size_t b = 0; b < f->outputs.size(); ++b) {
      const robodiff_output_desc& o = d.outputs[b];
      const OutputBlock& want = f->outputs[b];
      EXPECT_EQ(std::string(o.name), want.name);
      EXPECT_EQ(o.rows, want.rows);
      EXPECT_EQ(o.cols, want.cols);
      EXPECT_EQ(o.nnz, want.size());
      EXPECT_EQ(o.kind, want.kind == OutputKind::Sparse ? ROBODIFF_OUTPUT_SPARSE : ROBODIFF_OUTPUT_DENSE);
      if (want.kind == OutputKind::Sparse) {
        EXPECT_EQ(std::vector<std::uint32_t>(o.row_ptr, o.row_ptr + o.rows + 1), want.row_ptr);
        EXPECT_EQ(std::vector<std::uint32_t>(o.col_idx, o.col_idx + o.nnz), want.col_idx);
      } else {
        EXPECT_EQ(o.row_ptr, nullptr);
      }
    }
    EXPECT_EQ(fn.batchWidth(), 1u);
    constexpr std::uint64_t knots = 5;
    const auto in = randomInputs(*f, knots, 3);
    auto batched = outputBuffers(*f, knots);
    std::vector<double> work(fn.batchWorkSize() + fn.workSize() + 1);
    fn.evaluateBatch(knots, pointers(in, *f).data(), pointers(batched, *f).data(), work.data());
    for (std::uint64_t k = 0; k < knots; ++k) {
      auto single = outputBuffers(*f, 1);
      fn.evaluate(pointers(in, *f, k).data(), pointers(single, *f).data(), work.data());
      for (std::size_t b = 0; b < single.size(); ++b)
        for (std::size_t e = 0; e < single[b].size(); ++e)
          EXPECT_EQ(batched[b][k * single[b].size() + e], single[b][e]) << f->name << " knot " << k;
    }
  }
}

TEST(AsmBackend, WhatTheAssemblyDoesNotPrintStaysC) {
  SKIP_WITHOUT_ASSEMBLY();
  const detail::AsmTarget target = hostTargets().front();
  Graph g;
  const FunctionDefinition signs = everySign(g);
  const FunctionDefinition with_libm = randomFunction(g, "libm", 5, 60);  // exp, atan2, ... as calls
  ASSERT_TRUE(opsUsed(g, with_libm)[static_cast<int>(Op::Exp)] || opsUsed(g, with_libm)[static_cast<int>(Op::Atan2)]);
  EXPECT_FALSE(detail::generateAssemblyLibrary(g, {signs, with_libm}, withoutPairs(), target)) << "a libm call";
  EXPECT_FALSE(detail::generateAssemblyLibrary(g, {manyLiveValues(g, detail::kAssemblyBelow)}, withoutPairs(), target))
      << "a large function";
  FunctionDefinition blocks{"blocks", {}, {}};
  for (std::uint32_t b = 0; b < 8; ++b) {
    blocks.inputs.push_back({"x" + std::to_string(b), 1});
    blocks.outputs.push_back(
        OutputBlock::dense("y" + std::to_string(b), 1, 1, {g.binary(Op::Mul, g.input(b), g.constant(2.0))}));
  }
  EXPECT_FALSE(detail::generateAssemblyLibrary(g, {blocks}, withoutPairs(), target)) << "more blocks than registers";

  // Through generateLibrary: only a single-knot library asked for assembly gets it.
  CodegenOptions options;
  options.batch_width = 1;
  EXPECT_EQ(generateLibrary(g, {signs}, options).sources[0].path, "library.c") << "assembly not asked for";
  options.assembly = true;
  EXPECT_EQ(generateLibrary(g, {signs}, options).sources[0].path, "library.s");
  EXPECT_EQ(generateLibrary(g, {signs, with_libm}, options).sources[0].path, "library.c");
  options.batch_width = 0;
  EXPECT_EQ(generateLibrary(g, {signs}, options).sources[0].path, "library.c") << "batched code";
}

TEST(AsmBackend, GccAndClangAssembleTccDoesNot) {
  CompilerOptions options;
  options.compiler = "cc";
  EXPECT_TRUE(compilerAssembles(options));
  if (haveProgram("clang")) {
    options.compiler = "clang";
    EXPECT_TRUE(compilerAssembles(options));
  }
  if (haveProgram("tcc")) {
    options.compiler = "tcc";
    EXPECT_FALSE(compilerAssembles(options));
  }
}

TEST(AsmBackend, ClangAssemblesTheSameLibrary) {
  SKIP_WITHOUT_ASSEMBLY();
  if (!haveProgram("clang")) GTEST_SKIP() << "clang is not installed";
  Graph g;
  const FunctionDefinition f = chainFunction(g, "chain", 6);
  const GeneratedLibrary lib = assembly(g, {f}, hostTargets().back());
  TempDir dir;
  CompilerOptions options;
  options.compiler = "clang";
  const LoadedLibrary loaded = LoadedLibrary::open(compileLibrary(lib, dir / "clang.so", options).library);
  for (std::uint32_t seed = 1; seed <= 3; ++seed)
    expectGraphValuesAt(g, f, loaded.function("chain"), randomInputs(f, 1, seed), 1e-13, "clang");
}

}  // namespace
}  // namespace robodiff::codegen
