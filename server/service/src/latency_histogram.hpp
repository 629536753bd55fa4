#pragma once
// Latencies of one method as a fixed log-scale histogram: 8 buckets per power of two
// (each bucket at most 9% wide), lock-free (relaxed atomic counters), so recording costs
// a few instructions on a transport's hot path. Percentiles are read off the buckets
// (the bucket's upper bound, never above the largest latency seen).

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace robodiff::server::detail {

class LatencyHistogram {
 public:
  void record(std::uint64_t ns);

  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }
  std::uint64_t max() const { return max_.load(std::memory_order_relaxed); }
  // The latency under which `fraction` (0..1) of the recorded ones fall; 0 when none.
  std::uint64_t percentile(double fraction) const;

  // Cumulative counts for a metrics endpoint, from one snapshot of the buckets (so the
  // counts agree with each other): counts[i] = latencies whose bucket lies wholly at or
  // below bounds_ns[i] (ascending); a bucket straddling a bound is counted under the next
  // one (at most 9% off). total = every latency (the +Inf bucket), sum_ns their sum.
  struct Cumulative {
    std::vector<std::uint64_t> counts;
    std::uint64_t total = 0;
    std::uint64_t sum_ns = 0;
  };
  Cumulative cumulative(std::span<const std::uint64_t> bounds_ns) const;

  // The buckets holding latencies, ascending: (upper bound in ns, count). A reader that
  // keeps two of these apart in time gets the histogram of the latencies in between.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> occupied() const;

  // Bucket arithmetic, exposed for tests: index of a value, and a bucket's largest value.
  static std::size_t bucketOf(std::uint64_t ns);
  static std::uint64_t upperBound(std::size_t bucket);

  static constexpr unsigned kSubBits = 3;  // 2^3 = 8 buckets per power of two
  static constexpr std::size_t kBuckets = (64 - kSubBits + 1) << kSubBits;

 private:
  std::array<std::atomic<std::uint64_t>, kBuckets> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::uint64_t> max_{0};
  std::atomic<std::uint64_t> sum_{0};  // nanoseconds; wraps after 584 years of latency
};

}  // namespace robodiff::server::detail
