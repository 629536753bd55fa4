// Generated libraries called directly, one after the other in rounds: what the "direct
// calls" figures of docs/benchmarks.md and docs/code-generation.md measure. Each library's
// first function (or --function NAME) gets fixed inputs uniform in [-1, 1] and runs
// batches of single-knot calls; a round times every library once (the median of its
// batches, thread CPU time), and the table shows each library's median, fastest and
// slowest round. Inputs start --in-offset doubles past a page boundary and outputs at one
// (where a store and a later load of the same offset mod 4 KiB meet: 4K aliasing).
// Run by hand, never by ctest:
//   direct_calls [--rounds N] [--in-offset K] [--function NAME] LIB.so [LIB.so ...]
// Two sources of one function compiled two ways: copy the kept library (robodiff bench
// --keep, robodiff generate --out) and compile its src/ again with the other flags.
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "robodiff/codegen/loaded_library.hpp"

namespace {

using robodiff::codegen::CompiledFunction;
using robodiff::codegen::LoadedLibrary;

constexpr std::size_t kPage = 4096;

double threadSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Doubles starting `offset` doubles past a page boundary.
struct PageBuffer {
  PageBuffer(std::size_t doubles, std::size_t offset)
      : memory(static_cast<double*>(std::aligned_alloc(kPage, ((doubles + offset) * 8 / kPage + 1) * kPage)), &std::free),
        data(memory.get() + offset) {}
  std::unique_ptr<double, decltype(&std::free)> memory;
  double* data;
};

struct Subject {
  std::string path;
  LoadedLibrary library;
  CompiledFunction function;
  std::vector<PageBuffer> in, out;
  std::vector<const double*> in_pointers;
  std::vector<double*> out_pointers;
  std::vector<double> work;
  std::vector<double> rounds_ns;
};

Subject load(const std::string& path, const std::string& name, std::size_t in_offset) {
  LoadedLibrary library = LoadedLibrary::open(path);
  CompiledFunction function = library.function(name.empty() ? library.functionNames().at(0) : name);
  Subject s{path, std::move(library), function, {}, {}, {}, {}, std::vector<double>(function.workSize() + 1), {}};
  const auto& desc = function.descriptor();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (std::uint32_t b = 0; b < desc.n_inputs; ++b) {
    s.in.emplace_back(desc.inputs[b].size, in_offset);
    for (std::uint32_t k = 0; k < desc.inputs[b].size; ++k) s.in.back().data[k] = uniform(rng);
    s.in_pointers.push_back(s.in.back().data);
  }
  for (std::uint32_t b = 0; b < desc.n_outputs; ++b) {
    s.out.emplace_back(desc.outputs[b].nnz, 0);
    s.out_pointers.push_back(s.out.back().data);
  }
  return s;
}

// One round: the median over batches of calls, ns a call.
double timeRound(Subject& s) {
  constexpr int kBatches = 25, kCalls = 20000;
  std::vector<double> batches;
  for (int b = 0; b < kBatches; ++b) {
    const double t0 = threadSeconds();
    for (int c = 0; c < kCalls; ++c) {
      s.function.evaluate(s.in_pointers.data(), s.out_pointers.data(), s.work.data());
      asm volatile("" ::: "memory");  // each call's outputs count
    }
    batches.push_back((threadSeconds() - t0) / kCalls * 1e9);
  }
  std::nth_element(batches.begin(), batches.begin() + kBatches / 2, batches.end());
  return batches[kBatches / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int rounds = 5;
  std::size_t in_offset = 8;
  std::string name;
  std::vector<std::string> paths;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--rounds" && k + 1 < argc) rounds = std::max(1, std::atoi(argv[++k]));
    else if (a == "--in-offset" && k + 1 < argc) in_offset = static_cast<std::size_t>(std::atol(argv[++k]));
    else if (a == "--function" && k + 1 < argc) name = argv[++k];
    else if (!a.empty() && a[0] == '-') return std::fprintf(stderr, "direct_calls: unknown option %s\n", a.c_str()), 2;
    else paths.push_back(a);
  }
  if (paths.empty())
    return std::fprintf(stderr, "usage: direct_calls [--rounds N] [--in-offset K] [--function NAME] LIB.so ...\n"), 2;
  std::vector<Subject> subjects;
  try {
    for (const std::string& p : paths) subjects.push_back(load(p, name, in_offset));
  } catch (const std::exception& e) {
    return std::fprintf(stderr, "direct_calls: %s\n", e.what()), 1;
  }
  for (int r = 0; r < rounds; ++r)
    for (Subject& s : subjects) s.rounds_ns.push_back(timeRound(s));
  std::printf("| library | function | median ns | fastest round | slowest round |\n|---|---|---|---|---|\n");
  for (Subject& s : subjects) {
    std::vector<double>& v = s.rounds_ns;
    std::sort(v.begin(), v.end());
    std::printf("| %s | %s | %.2f | %.2f | %.2f |\n", s.path.c_str(), s.function.name().c_str(), v[v.size() / 2],
                v.front(), v.back());
  }
  return 0;
}
