// The sin-cos kernels' range checked once, at a function's entry (c_emitter.cpp): where
// every kernel takes an input and the function is small, the kernels run without
// checks of their own. Where every operation waits on a kernel, the kernels run at the
// entry and an argument beyond their range takes every lane through the checked kernel
// in a cold helper (entry_kernels.hpp); elsewhere it sends the call to a cold copy of the
// body with per-call checks (libm for that argument). Either way the values are those
// of the build without the entry check, bit for bit, whatever the argument and its
// position.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen {

double ulps(double got, double want);  // sincos_kernel_test.cpp

namespace {

using namespace testing;
using robodiff::testing::TempDir;

constexpr std::uint32_t kAngles = 7;
using Angles = std::array<double, kAngles>;

// sin q_j and cos q_j of seven angles, each times a running product of the sines before
// it: a chain as a robot's kinematics is. `links` more products per angle make the
// function larger without more kernels; `independent_work` adds q0 q1, an operation no
// kernel feeds (as a free-flyer's base rotation).
FunctionDefinition anglesFunction(Graph& g, std::uint32_t links = 0, bool independent_work = false) {
  std::vector<NodeId> values;
  NodeId product = g.one();
  for (std::uint32_t j = 0; j < kAngles; ++j) {
    const NodeId q = g.input(j);
    const NodeId s = g.unary(Op::Sin, q), c = g.unary(Op::Cos, q);
    product = g.binary(Op::Mul, product, s);
    for (std::uint32_t k = 0; k < links; ++k) product = g.binary(Op::Add, g.binary(Op::Mul, product, c), s);
    values.push_back(product);
    values.push_back(g.binary(Op::Mul, product, c));
  }
  if (independent_work) values.push_back(g.binary(Op::Mul, g.input(0), g.input(1)));
  const auto n = static_cast<std::uint32_t>(values.size());
  return FunctionDefinition{"angles", {{"q", kAngles}}, {OutputBlock::dense("v", n, 1, values)}};
}

struct Build {
  std::string source;
  LoadedLibrary library;
};

Build build(const Graph& g, const FunctionDefinition& f, const TempDir& dir, const std::string& name,
            const CodegenOptions& codegen = {}) {
  CompilerOptions options;
  options.native = true;
  GeneratedLibrary generated = generateLibrary(g, {f}, codegen);
  std::string source;
  for (const SourceFile& s : generated.sources) source += s.text;
  return {source, LoadedLibrary::open(compileLibrary(generated, dir / (name + ".so"), options).library)};
}

// The reference build: no lane pairs, so every kernel call checks its own argument.
Build perCallChecks(const Graph& g, const FunctionDefinition& f, const TempDir& dir) {
  CodegenOptions off;
  off.lane_pairs = false;
  Build b = build(g, f, dir, "per_call", off);
  EXPECT_EQ(b.source.find("_exact("), std::string::npos);
  return b;
}

constexpr std::uint32_t kMostOutputs = 2 * kAngles + 1;

std::vector<double> evaluate(const Build& b, const Angles& q) {
  std::vector<double> out(kMostOutputs, 0.0), work(4096);
  const double* in[] = {q.data()};
  double* outs[] = {out.data()};
  b.library.function("angles").evaluate(in, outs, work.data());
  return out;
}

// The paired single-knot entry point's text.
std::string pairedEval(const std::string& source) {
  const std::size_t start = source.find("#if RD_PAIRS\nRD_SCALAR_FN static void rd_angles_eval(");
  return start == std::string::npos ? std::string() : source.substr(start, source.find("#else", start) - start);
}

bool sameBits(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

TEST(EntryRangeCheck, KernelsEveryOperationWaitsOnRunAtEntryInOneBody) {
  Graph g;
  const FunctionDefinition f = anglesFunction(g);
  TempDir dir;
  const Build checked = build(g, f, dir, "checked");
  const std::string& s = checked.source;
  EXPECT_EQ(s.find("void rd_angles_in_range("), std::string::npos) << s;
  EXPECT_EQ(s.find("void rd_angles_exact("), std::string::npos) << "no cold copy of the body";
  const std::string body = pairedEval(s);
  ASSERT_FALSE(body.empty()) << s;
  EXPECT_NE(body.find("    rd_sincos_quad_in_range(rd_x0, rd_x1,"), std::string::npos) << body;
  EXPECT_NE(body.find("    rd_sincos_lanes_cold("), std::string::npos) << body;
  for (const char* checked_call : {"rd_sincos_quad(p", "rd_sincos_pair(p", "rd_sincos1("})
    EXPECT_EQ(body.find(checked_call), std::string::npos) << checked_call << " in\n" << body;
  for (std::uint32_t j = 0; j < kAngles; ++j)
    EXPECT_NE(body.find("in[0][" + std::to_string(j) + "]"), std::string::npos) << "angle " << j << ":\n" << body;
}

TEST(EntryRangeCheck, WorkNoKernelFeedsKeepsTheKernelsInTheBodyWithAColdCopy) {
  Graph g;
  const FunctionDefinition f = anglesFunction(g, 0, true);
  TempDir dir;
  const Build checked = build(g, f, dir, "checked");
  const std::string& s = checked.source;
  const std::size_t in_range = s.find("void rd_angles_in_range("), exact = s.find("void rd_angles_exact(");
  const std::size_t entry = s.find("void rd_angles_eval(", exact);
  ASSERT_NE(in_range, std::string::npos) << s;
  ASSERT_NE(exact, std::string::npos) << s;
  ASSERT_NE(entry, std::string::npos) << s;
  EXPECT_EQ(s.find("    rd_sincos_lanes_cold("), std::string::npos) << s;
  const std::string body = s.substr(in_range, exact - in_range);
  EXPECT_NE(body.find("rd_sincos_quad_in_range(p"), std::string::npos) << body;
  for (const char* checked_call : {"rd_sincos_quad(p", "rd_sincos_pair(p", "rd_sincos1("})
    EXPECT_EQ(body.find(checked_call), std::string::npos) << checked_call << " in\n" << body;
  const std::string check = s.substr(entry, s.find("\n}\n", entry) - entry);
  for (std::uint32_t j = 0; j < kAngles; ++j)
    EXPECT_NE(check.find("in[0][" + std::to_string(j) + "]"), std::string::npos) << "angle " << j << ":\n" << check;
}

// Each argument beyond the range, at each position, both ways: libm's sin and cos there,
// as the per-call checks give them. Without the cold paths the kernel returns garbage
// for 1e300.
TEST(EntryRangeCheck, AnArgumentBeyondTheRangeGivesThePerCallChecksValues) {
  for (const bool independent_work : {false, true}) {
    Graph g;
    const FunctionDefinition f = anglesFunction(g, 0, independent_work);
    TempDir dir;
    const Build checked = build(g, f, dir, "checked");
    const std::string cold_path = independent_work ? checked.source : pairedEval(checked.source);
    ASSERT_NE(cold_path.find(independent_work ? "void rd_angles_exact(" : "    rd_sincos_lanes_cold("),
              std::string::npos)
        << checked.source;
    const Build reference = perCallChecks(g, f, dir);
    const Angles ordinary = {0.3, -2.5, 7.0, 1.25, -0.75, 100.0, 2.0};
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (double far : {0x1p19, std::nextafter(0x1p19, INFINITY), -1e17, 3e30, 1e300, double(INFINITY), nan}) {
      for (std::uint32_t j = 0; j < kAngles; ++j) {
        Angles q = ordinary;
        q[j] = far;
        const std::vector<double> got = evaluate(checked, q), want = evaluate(reference, q);
        for (std::uint32_t k = 0; k < kMostOutputs; ++k)
          EXPECT_TRUE(sameBits(got[k], want[k])) << "q[" << j << "] = " << far << ", value " << k << ": " << got[k]
                                                 << " against " << want[k] << (independent_work ? ", cold copy" : "");
        if (!std::isfinite(far)) continue;
        const double c = std::cos(far);
        EXPECT_LE(ulps(got[2 * j + 1] / got[2 * j], c), 4.0) << "cos q[" << j << "] = " << far;
      }
    }
    const std::vector<double> got = evaluate(checked, ordinary), want = evaluate(reference, ordinary);
    for (std::uint32_t k = 0; k < kMostOutputs; ++k) EXPECT_EQ(got[k], want[k]) << "value " << k;
  }
}

// sin(q0 + q1): a computed argument, so every kernel checks its own.
TEST(EntryRangeCheck, ComputedArgumentsKeepTheKernelsChecks) {
  Graph g;
  std::vector<NodeId> values;
  for (std::uint32_t j = 0; j < 3; ++j) {
    const NodeId x = g.binary(Op::Add, g.input(j), g.input(j + 1));
    values.push_back(g.unary(Op::Sin, x));
    values.push_back(g.unary(Op::Cos, x));
  }
  const FunctionDefinition f{"sums", {{"q", 4}}, {OutputBlock::dense("v", 6, 1, values)}};
  TempDir dir;
  const Build b = build(g, f, dir, "sums");
  EXPECT_EQ(b.source.find("_exact("), std::string::npos);
  EXPECT_EQ(b.source.find("_in_range(p"), std::string::npos);
  const std::array<double, 4> q = {1e300, 0.5, -0.25, 3e30};
  std::vector<double> out(6), work(4096);
  const double* in[] = {q.data()};
  double* outs[] = {out.data()};
  b.library.function("sums").evaluate(in, outs, work.data());
  for (std::uint32_t j = 0; j < 3; ++j) {
    EXPECT_LE(ulps(out[2 * j], std::sin(q[j] + q[j + 1])), 2.0) << j;
    EXPECT_LE(ulps(out[2 * j + 1], std::cos(q[j] + q[j + 1])), 2.0) << j;
  }
}

// Above the size where it was measured to pay, the kernels keep their checks (one body).
TEST(EntryRangeCheck, LargerFunctionsKeepTheKernelsChecks) {
  Graph g;
  const FunctionDefinition f = anglesFunction(g, 30);
  ASSERT_GE(generateLibrary(g, {f}).functions.at(0).operations, 256u);
  TempDir dir;
  const Build b = build(g, f, dir, "larger");
  EXPECT_EQ(b.source.find("_exact("), std::string::npos);
  EXPECT_EQ(b.source.find("    rd_sincos_lanes_cold("), std::string::npos);
  const Build reference = perCallChecks(g, f, dir);
  Angles q = {0.3, -2.5, 1e300, 1.25, -0.75, 100.0, 2.0};
  const std::vector<double> got = evaluate(b, q), want = evaluate(reference, q);
  for (std::uint32_t k = 0; k < kMostOutputs; ++k) EXPECT_TRUE(sameBits(got[k], want[k])) << k;
}

}  // namespace
}  // namespace robodiff::codegen
