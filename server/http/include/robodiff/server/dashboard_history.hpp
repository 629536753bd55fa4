#pragma once
// The dashboard's recent history, kept by the server so that a page opened now draws its
// charts at once: a thread of its own samples the service's fine latency histograms every
// interval (1 s, the page's refresh), turns two consecutive samples into one point (p50 and
// p99 of Evaluate and EvaluateBatch in that interval, and requests per second) and keeps
// the latest `capacity` points (600: 10 minutes) in a RecentRing. GET /api/history serves
// them (dashboard_routes.cpp; docs/service.md, "The dashboard").

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "robodiff/server/recent_ring.hpp"
#include "robodiff/server/service.hpp"

namespace robodiff::server {

// One interval of the charts. Latencies in microseconds, none when no call ended in it.
struct HistoryPoint {
  double unix_seconds = 0;  // the interval's end
  std::optional<double> evaluate_p50_us, evaluate_p99_us, batch_p50_us, batch_p99_us;
  double evaluate_per_second = 0, batch_per_second = 0, other_per_second = 0;
};

// The point of the interval between two samples of Service::requestLatencies() taken
// `interval_seconds` apart (both since start: their difference is the interval's).
HistoryPoint historyPoint(const std::vector<ServiceOverview::MethodLatency>& before,
                          const std::vector<ServiceOverview::MethodLatency>& now, double interval_seconds,
                          double unix_seconds);

struct DashboardHistoryOptions {
  std::chrono::milliseconds interval = std::chrono::seconds(1);
  std::size_t capacity = 600;  // points kept: capacity x interval of history
};

class DashboardHistory {
 public:
  // Starts sampling `service`, which must outlive this. Throws std::invalid_argument for a
  // zero interval or capacity.
  explicit DashboardHistory(const Service& service, DashboardHistoryOptions options = {});
  ~DashboardHistory();  // stops the thread
  DashboardHistory(const DashboardHistory&) = delete;
  DashboardHistory& operator=(const DashboardHistory&) = delete;

  // The points after `after_unix_seconds`, oldest first.
  std::vector<HistoryPoint> points(double after_unix_seconds = -std::numeric_limits<double>::infinity()) const;
  const DashboardHistoryOptions& options() const { return options_; }

 private:
  void run();

  const Service& service_;
  const DashboardHistoryOptions options_;
  RecentRing<HistoryPoint> ring_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;  // last: it uses everything above
};

// GET /api/history as JSON: {"interval_seconds", "capacity", "points": [{"t", "latency":
// {"Evaluate p50": us or null, ...}, "rate": {"Evaluate": per s, ...}}]}: the points the
// page draws, after `after_unix_seconds`.
std::string historyJson(const DashboardHistory& history,
                        double after_unix_seconds = -std::numeric_limits<double>::infinity());

}  // namespace robodiff::server
