// Not a benchmark suite (bench/ is for those): one quick measurement printed, never
// asserted, of the interpreter against compiled code on a ~2000-node graph.
#include <chrono>
#include <cstdio>
#include <functional>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using Clock = std::chrono::steady_clock;

// Nanoseconds per call of `call`, the best of a few rounds of ~20 ms.
double nanosecondsPerCall(const std::function<void()>& call, double per = 1.0) {
  std::uint64_t reps = 1;
  for (;;) {  // calibrate
    const auto t0 = Clock::now();
    for (std::uint64_t i = 0; i < reps; ++i) call();
    if (Clock::now() - t0 > std::chrono::milliseconds(5)) break;
    reps *= 2;
  }
  reps *= 4;
  double best = 1e300;
  for (int round = 0; round < 3; ++round) {
    const auto t0 = Clock::now();
    for (std::uint64_t i = 0; i < reps; ++i) call();
    best = std::min(best, std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / reps / per);
  }
  return best;
}

TEST(Measurement, InterpreterAgainstCompiledCode) {
  Graph g;
  FunctionDefinition f = chainFunction(g, "fk", 40);  // rotations and positions: ~2000 nodes
  const Interpreter interpreter(g, f);
  const auto info = generateLibrary(g, {f}).functions.at(0);
  std::printf("\n  graph: %u nodes needed, %u operations, %u sin/cos pairs, %zu interpreter instructions\n",
              info.needed_nodes, info.operations, info.sincos_pairs, interpreter.instructionCount());

  constexpr std::uint64_t kBatch = 256;
  const auto in = randomInputs(f, kBatch, 3);
  auto out = outputBuffers(f, kBatch);
  const auto ip = pointers(in, f);
  const auto op = pointers(out, f);
  std::vector<double> iwork(interpreter.workSize());
  const double interpreted = nanosecondsPerCall([&] { interpreter.evaluate(ip.data(), op.data(), iwork.data()); });
  std::printf("  %-32s %10s %12s %14s\n", "evaluator", "compile s", "ns / call", "batched ns/knot");
  std::printf("  %-32s %10s %12.0f %14s\n", "interpreter", "-", interpreted, "-");

  struct Build {
    const char* label;
    std::string compiler;
    OptimizationLevel level;
    bool native;
  };
  for (const Build& b : {Build{"tcc", "tcc", OptimizationLevel::O1, false},
                         Build{"gcc -O2", "gcc", OptimizationLevel::O2, false},
                         Build{"gcc -O2 -march=native", "gcc", OptimizationLevel::O2, true},
                         Build{"clang -O2 -march=native", "clang", OptimizationLevel::O2, true}}) {
    if (!haveProgram(b.compiler)) continue;
    TempDir dir;
    CompilerOptions options;
    options.compiler = b.compiler;
    options.optimization = b.level;
    options.native = b.native;
    const CompileReport report = compileLibrary(generateLibrary(g, {f}), dir / "fk.so", options);
    LoadedLibrary lib = LoadedLibrary::open(report.library);
    const CompiledFunction compiled = lib.function("fk");
    std::vector<double> work(compiled.workSize() + 1), bwork(compiled.batchWorkSize() + 1);
    const double single = nanosecondsPerCall([&] { compiled.evaluate(ip.data(), op.data(), work.data()); });
    const double batched = nanosecondsPerCall(
        [&] { compiled.evaluateBatch(kBatch, ip.data(), op.data(), bwork.data()); }, static_cast<double>(kBatch));
    char label[64];
    std::snprintf(label, sizeof label, "%s (W=%u)", b.label, compiled.batchWidth());
    std::printf("  %-32s %10.2f %12.0f %14.0f   interpreter / compiled = %.1fx\n", label, report.seconds, single,
                batched, interpreted / single);
  }
}

}  // namespace
}  // namespace robodiff::codegen
