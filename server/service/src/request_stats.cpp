#include "request_stats.hpp"

#include <algorithm>

namespace robodiff::server::detail {

RequestStats::Transport& RequestStats::transport(std::string_view name) {
  const std::size_t published = transport_count_.load(std::memory_order_acquire);
  for (std::size_t i = 0; i < published; ++i)
    if (transports_[i].name == name) return transports_[i];
  std::lock_guard lock(transport_mutex_);
  const std::size_t n = transport_count_.load(std::memory_order_relaxed);
  for (std::size_t i = published; i < n; ++i)
    if (transports_[i].name == name) return transports_[i];
  if (n == kMaxTransports) return transports_[kMaxTransports - 1];  // "other" collects the rest
  Transport& slot = transports_[n];
  slot.name = n + 1 == kMaxTransports ? std::string("other") : std::string(name);
  transport_count_.store(n + 1, std::memory_order_release);
  return slot;
}

void RequestStats::record(std::string_view transport_name, rpc::Method method, StatusCode code,
                          std::chrono::nanoseconds latency) {
  const auto m = static_cast<std::size_t>(method);
  const bool error = code != StatusCode::Ok;
  if (m < methods_.size()) {
    methods_[m].latency.record(static_cast<std::uint64_t>(std::max<std::int64_t>(latency.count(), 0)));
    if (error) methods_[m].errors.fetch_add(1, std::memory_order_relaxed);
    methods_[m].codes[std::min<std::size_t>(static_cast<std::size_t>(code), kStatusCodeCount)].fetch_add(
        1, std::memory_order_relaxed);
  }
  if (error)
    codes_[std::min<std::size_t>(static_cast<std::size_t>(code), kStatusCodeCount)].fetch_add(
        1, std::memory_order_relaxed);
  Transport& t = transport(transport_name);
  t.requests.fetch_add(1, std::memory_order_relaxed);
  if (error) t.errors.fetch_add(1, std::memory_order_relaxed);
}

std::vector<rpc::MethodStats> RequestStats::methods() const {
  std::vector<rpc::MethodStats> out;
  for (std::uint32_t m = 0; m < rpc::kMethodCount; ++m) {
    const Method& s = methods_[m];
    rpc::MethodStats r;
    r.method = static_cast<rpc::Method>(m);
    r.requests = s.latency.count();
    r.errors = s.errors.load(std::memory_order_relaxed);
    r.p50_ns = s.latency.percentile(0.50);
    r.p90_ns = s.latency.percentile(0.90);
    r.p99_ns = s.latency.percentile(0.99);
    r.max_ns = s.latency.max();
    out.push_back(r);
  }
  return out;
}

std::vector<rpc::StatusCount> RequestStats::errors() const {
  std::vector<rpc::StatusCount> out;
  for (std::uint32_t c = 1; c < kStatusCodeCount; ++c)
    if (const std::uint64_t n = codes_[c].load(std::memory_order_relaxed); n != 0)
      out.push_back({static_cast<StatusCode>(c), n});
  // Codes this build does not know are reported as UNKNOWN.
  if (const std::uint64_t n = codes_[kStatusCodeCount].load(std::memory_order_relaxed); n != 0) {
    auto it =
        std::find_if(out.begin(), out.end(), [](const rpc::StatusCount& s) { return s.code == StatusCode::Unknown; });
    if (it != out.end())
      it->count += n;
    else
      out.push_back({StatusCode::Unknown, n});
  }
  return out;
}

std::vector<rpc::TransportCounts> RequestStats::transports() const {
  std::vector<rpc::TransportCounts> out;
  const std::size_t n = transport_count_.load(std::memory_order_acquire);
  for (std::size_t i = 0; i < n; ++i)
    out.push_back({transports_[i].name, transports_[i].requests.load(std::memory_order_relaxed),
                   transports_[i].errors.load(std::memory_order_relaxed)});
  return out;
}

std::uint64_t RequestStats::replies(rpc::Method method, std::size_t code) const {
  const auto m = static_cast<std::size_t>(method);
  if (m >= methods_.size() || code > kStatusCodeCount) return 0;
  return methods_[m].codes[code].load(std::memory_order_relaxed);
}

const LatencyHistogram& RequestStats::latency(rpc::Method method) const {
  return methods_.at(static_cast<std::size_t>(method)).latency;
}

}  // namespace robodiff::server::detail
