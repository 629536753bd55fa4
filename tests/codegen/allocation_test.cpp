// Evaluation allocates nothing: malloc and friends are interposed for this test
// executable (forwarding to glibc) and counted while an evaluation runs.
#include <atomic>
#include <cstddef>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void __libc_free(void*);
}

namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
void count() {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* malloc(std::size_t n) {
  count();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  count();
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
}

namespace robodiff::codegen {
namespace {

using namespace testing;

// Counts allocations made while `body` runs.
template <class Body>
long allocationsDuring(Body body) {
  allocations = 0;
  counting = true;
  body();
  counting = false;
  return allocations.load();
}

TEST(Allocation, TheCounterSeesAllocations) {
  EXPECT_GT(allocationsDuring([] { delete new std::vector<double>(100); }), 0);
}

TEST(Allocation, EvaluationAllocatesNothing) {
  Graph g;
  FunctionDefinition f = randomFunction(g, "f", 3, 200);
  CodegenOptions codegen;
  codegen.split_threshold = 150;  // the parts' hand-over through the work buffer too
  TempDir dir;
  CompilerOptions options;
  options.compiler = "gcc";
  options.optimization = OptimizationLevel::O1;
  LoadedLibrary lib = LoadedLibrary::open(compileLibrary(generateLibrary(g, {f}, codegen), dir / "f.so", options).library);
  const CompiledFunction compiled = lib.function("f");
  const Interpreter interpreter(g, f);

  constexpr std::uint64_t n = 11;
  const auto in = randomInputs(f, n, 1);
  auto out = outputBuffers(f, n);
  const auto ip = pointers(in, f);
  const auto op = pointers(out, f);
  std::vector<double> work(compiled.workSize()), bwork(compiled.batchWorkSize()), iwork(interpreter.workSize());

  EXPECT_EQ(allocationsDuring([&] {
              for (int i = 0; i < 10; ++i) {
                compiled.evaluate(ip.data(), op.data(), work.data());
                compiled.evaluateBatch(n, ip.data(), op.data(), bwork.data());
                interpreter.evaluate(ip.data(), op.data(), iwork.data());
                interpreter.evaluateBatch(n, ip.data(), op.data(), iwork.data());
              }
            }),
            0);
}

}  // namespace
}  // namespace robodiff::codegen
