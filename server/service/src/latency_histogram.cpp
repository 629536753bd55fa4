#include "latency_histogram.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace robodiff::server::detail {

// Values below 2^kSubBits have a bucket each; above, a power of two [2^e, 2^(e+1)) is cut
// into 2^kSubBits equal buckets by the bits that follow the leading one.
std::size_t LatencyHistogram::bucketOf(std::uint64_t ns) {
  constexpr std::uint64_t sub = std::uint64_t{1} << kSubBits;
  if (ns < sub) return static_cast<std::size_t>(ns);
  const unsigned e = 63u - static_cast<unsigned>(std::countl_zero(ns));  // ns in [2^e, 2^(e+1))
  const std::uint64_t mantissa = (ns >> (e - kSubBits)) & (sub - 1);
  return static_cast<std::size_t>(((e - kSubBits + 1) << kSubBits) + mantissa);
}

std::uint64_t LatencyHistogram::upperBound(std::size_t bucket) {
  constexpr std::uint64_t sub = std::uint64_t{1} << kSubBits;
  if (bucket < sub) return bucket;
  const unsigned e = static_cast<unsigned>(bucket >> kSubBits) + kSubBits - 1;
  const std::uint64_t mantissa = bucket & (sub - 1);
  const std::uint64_t low = (std::uint64_t{1} << e) + (mantissa << (e - kSubBits));
  const std::uint64_t width = std::uint64_t{1} << (e - kSubBits);
  return low + (width - 1);  // may wrap only for the very last bucket: then it is UINT64_MAX
}

void LatencyHistogram::record(std::uint64_t ns) {
  buckets_[bucketOf(ns)].fetch_add(1, std::memory_order_relaxed);
  count_.fetch_add(1, std::memory_order_relaxed);
  sum_.fetch_add(ns, std::memory_order_relaxed);
  std::uint64_t seen = max_.load(std::memory_order_relaxed);
  while (ns > seen && !max_.compare_exchange_weak(seen, ns, std::memory_order_relaxed)) {
  }
}

std::uint64_t LatencyHistogram::percentile(double fraction) const {
  std::array<std::uint64_t, kBuckets> snapshot;
  std::uint64_t total = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) total += snapshot[b] = buckets_[b].load(std::memory_order_relaxed);
  if (total == 0) return 0;
  const double clamped = std::clamp(fraction, 0.0, 1.0);
  const auto rank =
      std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(clamped * static_cast<double>(total))));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) {
    seen += snapshot[b];
    if (seen >= rank) return std::min(upperBound(b), max());
  }
  return max();
}

std::vector<std::pair<std::uint64_t, std::uint64_t>> LatencyHistogram::occupied() const {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> out;
  for (std::size_t b = 0; b < kBuckets; ++b)
    if (const std::uint64_t n = buckets_[b].load(std::memory_order_relaxed); n != 0) out.emplace_back(upperBound(b), n);
  return out;
}

LatencyHistogram::Cumulative LatencyHistogram::cumulative(std::span<const std::uint64_t> bounds_ns) const {
  Cumulative out;
  out.counts.assign(bounds_ns.size(), 0);
  out.sum_ns = sum_.load(std::memory_order_relaxed);
  std::size_t bound = 0;  // the first bound this bucket may count under
  for (std::size_t b = 0; b < kBuckets; ++b) {
    const std::uint64_t n = buckets_[b].load(std::memory_order_relaxed);
    out.total += n;
    if (n == 0) continue;
    while (bound < bounds_ns.size() && upperBound(b) > bounds_ns[bound]) ++bound;
    if (bound < bounds_ns.size()) out.counts[bound] += n;
  }
  for (std::size_t i = 1; i < out.counts.size(); ++i) out.counts[i] += out.counts[i - 1];
  return out;
}

}  // namespace robodiff::server::detail
