#pragma once
// What recordRequest accounts for Health: per method the requests, the errors and the
// latency histogram; the non-OK replies by status code; the requests and errors per
// transport. Recording is lock-free (a transport is found among the known ones by a
// scan of published slots; only a transport's first request takes a lock).

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "latency_histogram.hpp"
#include "robodiff/schema/messages.hpp"

namespace robodiff::server::detail {

class RequestStats {
 public:
  void record(std::string_view transport, rpc::Method method, StatusCode code, std::chrono::nanoseconds latency);

  std::vector<rpc::MethodStats> methods() const;         // one per method, in Method order
  std::vector<rpc::StatusCount> errors() const;          // non-OK codes seen
  std::vector<rpc::TransportCounts> transports() const;  // in the order first seen

  // For a metrics endpoint: a method's replies with one status code (kStatusCodeCount:
  // codes unknown to this build), and its latency histogram.
  std::uint64_t replies(rpc::Method method, std::size_t code) const;
  const LatencyHistogram& latency(rpc::Method method) const;

  static constexpr std::size_t kMaxTransports = 16;  // beyond: counted under "other"

 private:
  struct Method {
    LatencyHistogram latency;
    std::atomic<std::uint64_t> errors{0};
    std::array<std::atomic<std::uint64_t>, kStatusCodeCount + 1> codes{};  // replies by status, OK included
  };
  struct Transport {
    std::string name;  // written before the slot is published, never after
    std::atomic<std::uint64_t> requests{0}, errors{0};
  };
  Transport& transport(std::string_view name);

  std::array<Method, rpc::kMethodCount> methods_;
  std::array<std::atomic<std::uint64_t>, kStatusCodeCount + 1> codes_{};  // last: codes unknown to this build
  std::array<Transport, kMaxTransports> transports_;
  std::atomic<std::size_t> transport_count_{0};  // slots [0, count) are published
  std::mutex transport_mutex_;                   // adding a slot
};

}  // namespace robodiff::server::detail
