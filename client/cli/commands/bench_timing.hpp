// Timing for `robodiff bench`: seconds per call as the median of a few batches of
// calls (thread CPU time), each batch sized to a fixed length after a warm-up that also
// calibrates the batch size; the throughput of a batch split over threads (wall clock);
// and the aligned buffers the calls read and write.
#pragma once

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <new>
#include <thread>
#include <vector>

namespace robodiff::cli::bench {

struct TimingPlan {
  double batch_seconds = 0.02;  // length of one measured batch of calls
  int batches = 7;              // the median of these is reported

  static TimingPlan full() { return {0.02, 7}; }
  static TimingPlan quick() { return {0.003, 3}; }
};

// Keeps `value` (and everything reachable from memory) alive as far as the optimiser
// knows: the call that produced it cannot be elided or hoisted out of a loop.
template <class T> inline void doNotOptimize(const T& value) { asm volatile("" : : "g"(&value) : "memory"); }

// Doubles on 64-byte boundaries, as Eigen allocates them where AVX-512 is enabled: a
// caller's aligned output gets aligned vector stores (docs/code-generation.md).
template <class T> struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlignment{64};
  CacheLineAllocator() = default;
  template <class U> CacheLineAllocator(const CacheLineAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlignment)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, kAlignment); }
  template <class U> bool operator==(const CacheLineAllocator<U>&) const { return true; }
  template <class U> bool operator!=(const CacheLineAllocator<U>&) const { return false; }
};
using AlignedDoubles = std::vector<double, CacheLineAllocator<double>>;

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

inline double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// CPU time of the calling thread: what a single-threaded measurement counts, so that
// the time the thread spends descheduled on a shared machine is not charged to the
// code under test (wall clock is used where threads run in parallel).
inline double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Calls f() `n` times and returns the thread CPU seconds it took.
template <class F> double timeCalls(F& f, std::uint64_t n) {
  const double t0 = threadCpuSeconds();
  for (std::uint64_t i = 0; i < n; ++i) f();
  return threadCpuSeconds() - t0;
}

// How many calls of f() fill `seconds`: doubles the count until a run lasts a quarter
// of it (the warm-up: caches, branch predictors, clock frequency), then scales.
template <class F> std::uint64_t callsFilling(F& f, double seconds) {
  std::uint64_t n = 1;
  for (;;) {
    const double t = timeCalls(f, n);
    if (t >= seconds / 4 || n >= (std::uint64_t{1} << 40)) {
      const double per_call = std::max(t / static_cast<double>(n), 1e-10);
      return std::max<std::uint64_t>(1, static_cast<std::uint64_t>(seconds / per_call));
    }
    n *= 2;
  }
}

// Seconds per call of f(): the median over plan.batches batches of ~plan.batch_seconds.
template <class F> double secondsPerCall(F f, const TimingPlan& plan) {
  const std::uint64_t n = callsFilling(f, plan.batch_seconds);
  std::vector<double> per_call;
  for (int b = 0; b < plan.batches; ++b) per_call.push_back(timeCalls(f, n) / static_cast<double>(n));
  return median(per_call);
}

// Throughput of `threads` threads sharing `knots` knots: slice(t, begin, end) evaluates
// knots [begin, end) on thread t (with that thread's own work buffer). Each measured
// batch starts the threads, lets each one evaluate its slice `passes` times with no
// synchronisation in between, and joins them; the result is the median of wall time /
// (passes * knots), in seconds per knot. `seconds_per_pass` (one thread, the whole
// batch) sizes the passes to ~plan.batch_seconds.
template <class Slice> double secondsPerKnotOnThreads(Slice slice, unsigned threads, std::uint64_t knots,
                                                      double seconds_per_pass, const TimingPlan& plan) {
  threads = std::max(1u, threads);
  auto run = [&](std::uint64_t passes) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t)
      pool.emplace_back([&, t] {
        const std::uint64_t begin = knots * t / threads, end = knots * (t + 1) / threads;
        for (std::uint64_t p = 0; p < passes; ++p) slice(t, begin, end);
      });
    for (std::thread& th : pool) th.join();
    return secondsSince(t0);
  };
  const double per_pass_guess = std::max(seconds_per_pass / threads, 1e-9);
  const std::uint64_t passes =
      std::max<std::uint64_t>(1, static_cast<std::uint64_t>(plan.batch_seconds / per_pass_guess));
  run(std::max<std::uint64_t>(1, passes / 4));  // warm-up
  std::vector<double> per_knot;
  for (int b = 0; b < plan.batches; ++b) per_knot.push_back(run(passes) / static_cast<double>(passes * knots));
  return median(per_knot);
}

}  // namespace robodiff::cli::bench
