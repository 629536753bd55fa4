// The inline sin-and-cos kernel (sincos_kernel.h) against libm's sincos: within 2 ulp
// over joint-angle ranges, near multiples of pi/2 and for tiny arguments, libm's own
// values beyond its range, NaN for NaN and infinities. And the batched code's SIMD
// variant: lanes that mix in-range and out-of-range arguments give what the single
// call gives.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/codegen/sincos_kernel.h"

namespace robodiff::codegen {

// Units in the last place of `want` between got and want (0 when equal, NaN == NaN).
double ulps(double got, double want) {
  if (std::isnan(got) && std::isnan(want)) return 0.0;
  if (got == want) return 0.0;
  const double ulp = std::nextafter(std::fabs(want), INFINITY) - std::fabs(want);
  return std::fabs(got - want) / (want == 0.0 ? std::numeric_limits<double>::denorm_min() : ulp);
}

namespace {

using namespace testing;

// The largest difference from libm (in ulp, of sin or cos) over the arguments added.
struct Worst {
  double ulps = 0.0;
  double at = 0.0;
  void add(double x) {
    double s, c, ls, lc;
    rd_sincos1(x, &s, &c);
    ::sincos(x, &ls, &lc);
    const double e = std::max(robodiff::codegen::ulps(s, ls), robodiff::codegen::ulps(c, lc));
    if (e > ulps) {
      ulps = e;
      at = x;
    }
  }
};

TEST(SincosKernel, WithinTwoUlpOfLibmOverJointAngles) {
  std::mt19937_64 rng(11);
  Worst w;
  std::uniform_real_distribution<double> angle(-4.0 * M_PI, 4.0 * M_PI);
  for (int i = 0; i < 1000000; ++i) w.add(angle(rng));
  EXPECT_LE(w.ulps, 2.0) << "at x = " << w.at;
  Worst wide;
  std::uniform_real_distribution<double> far(-0x1p19, 0x1p19);
  for (int i = 0; i < 200000; ++i) wide.add(far(rng));
  EXPECT_LE(wide.ulps, 2.0) << "at x = " << wide.at;
}

TEST(SincosKernel, NearMultiplesOfHalfPiAndTinyArguments) {
  Worst w;
  // Where sin or cos is tiny: the reduction must keep its relative accuracy.
  for (int k = -100000; k <= 100000; k += 7) {
    const double x = k * (M_PI / 2.0);
    for (double d : {0.0, 1e-12, -1e-9, 3e-7})
      for (double y : {x + d, std::nextafter(x + d, INFINITY), std::nextafter(x + d, -INFINITY)}) w.add(y);
  }
  EXPECT_LE(w.ulps, 2.0) << "at x = " << w.at;
  Worst tiny;
  for (double x = 1e-300; x < 1e-3; x *= 1.7) {
    tiny.add(x);
    tiny.add(-x);
  }
  tiny.add(std::numeric_limits<double>::denorm_min());
  EXPECT_LE(tiny.ulps, 1.0) << "at x = " << tiny.at;
  for (double zero : {0.0, -0.0}) {  // (the sign of sin(-0) is not kept)
    double s, c;
    rd_sincos1(zero, &s, &c);
    EXPECT_EQ(s, 0.0);
    EXPECT_EQ(c, 1.0);
  }
}

TEST(SincosKernel, BeyondItsRangeItIsLibm) {
  for (double x : {0x1p19 * 1.0000001, 1e7, -3.3e12, 1e300, -std::numeric_limits<double>::max()}) {
    double s, c, ls, lc;
    rd_sincos1(x, &s, &c);
    ::sincos(x, &ls, &lc);
    EXPECT_EQ(s, ls) << x;
    EXPECT_EQ(c, lc) << x;
  }
  for (double x : {std::numeric_limits<double>::quiet_NaN(), double(INFINITY), -double(INFINITY)}) {
    double s = 0.0, c = 0.0;
    rd_sincos1(x, &s, &c);
    EXPECT_TRUE(std::isnan(s) && std::isnan(c)) << x;
  }
}

// The vector variant (RD_SC_VECTOR: the quadrant's signs set before the polynomials' last
// operations, only the swap after them) against the one-argument kernel (signs and swap
// after), bit for bit: changing a sign is exact, so the two orders must agree wherever
// the compiler contracts the same operations (here, none: no FMA target).
typedef double ScQuad __attribute__((vector_size(32)));
typedef unsigned long long ScQuadBits __attribute__((vector_size(32)));

TEST(SincosKernel, VectorLanesAreTheOneArgumentKernelBitForBit) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> joint(-10.0, 10.0), far(-0x1p19, 0x1p19), tiny(-1e-6, 1e-6);
  std::uniform_int_distribution<int> quarter(-40000, 40000);
  std::size_t differing = 0, lanes = 0;
  for (int i = 0; i < 200000; ++i) {
    const ScQuad x = {joint(rng), far(rng), tiny(rng), quarter(rng) * (M_PI / 2.0)};
    ScQuad s, c;
    RD_SC_VECTOR(ScQuad, ScQuadBits, x, s, c);
    for (int l = 0; l < 4; ++l, ++lanes) {
      double one_s, one_c;
      rd_sincos1_in_range(x[l], &one_s, &one_c);
      const double vs = s[l], vc = c[l];
      if (std::memcmp(&one_s, &vs, sizeof vs) != 0 || std::memcmp(&one_c, &vc, sizeof vc) != 0) {
        if (differing++ < 3) ADD_FAILURE() << "x = " << x[l] << ": " << vs << ", " << vc << " vs " << one_s << ", " << one_c;
      }
    }
  }
  EXPECT_EQ(differing, 0u) << "of " << lanes << " lanes";
}

// sin and cos of one input, compiled: the batched variant (every SIMD lane at once)
// against the single call, with lanes beyond the kernel's range among ordinary ones.
TEST(SincosKernel, BatchedLanesMatchTheSingleCall) {
  Graph g;
  const auto x = g.input(0);
  FunctionDefinition f{"sc", {{"x", 1}},
                       {OutputBlock::dense("y", 2, 1, {g.unary(Op::Sin, x), g.unary(Op::Cos, x)})}};
  TempDir dir;
  const CompileReport report = compileLibrary(generateLibrary(g, {f}), dir / "sc.so");
  const LoadedLibrary lib = LoadedLibrary::open(report.library);
  const CompiledFunction fn = lib.function("sc");
  const std::vector<double> xs = {0.3,  -2.5, 1e6,  std::numeric_limits<double>::quiet_NaN(), 7.0,  -0.0, double(INFINITY), 0x1p19,
                                  1.25, 3e9,  -1.0, 100.0, 5e-8, 2.0, -3.0, 0.75, M_PI / 2.0};
  std::vector<double> batched(2 * xs.size(), -1.0), work(fn.batchWorkSize() + fn.workSize() + 1);
  const double* in[] = {xs.data()};
  double* out[] = {batched.data()};
  fn.evaluateBatch(xs.size(), in, out, work.data());
  for (std::size_t k = 0; k < xs.size(); ++k) {
    double single[2];
    const double* sin_in[] = {&xs[k]};
    double* sin_out[] = {single};
    fn.evaluate(sin_in, sin_out, work.data());
    double ls, lc;
    ::sincos(xs[k], &ls, &lc);
    EXPECT_LE(ulps(single[0], ls), 2.0) << "sin " << xs[k];
    EXPECT_LE(ulps(single[1], lc), 2.0) << "cos " << xs[k];
    // FMA contraction may differ between the scalar and vector code: 2 ulp.
    EXPECT_LE(ulps(batched[2 * k], single[0]), 2.0) << "batched sin " << xs[k];
    EXPECT_LE(ulps(batched[2 * k + 1], single[1]), 2.0) << "batched cos " << xs[k];
  }
}

}  // namespace
}  // namespace robodiff::codegen
