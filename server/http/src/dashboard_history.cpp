// The dashboard's history: points from differenced histograms, the sampling thread, JSON.
#include "robodiff/server/dashboard_history.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace robodiff::server {
namespace {

using Buckets = std::vector<std::pair<std::uint64_t, std::uint64_t>>;  // (upper bound ns, count), ascending

const Buckets* bucketsOf(const std::vector<ServiceOverview::MethodLatency>& sample, rpc::Method method) {
  for (const auto& m : sample)
    if (m.method == method) return &m.buckets;
  return nullptr;
}

// now - before, bucket by bucket (both ascending by bound); empty buckets left out.
Buckets difference(const Buckets& now, const Buckets* before) {
  Buckets out;
  std::size_t j = 0;
  for (const auto& [upper, count] : now) {
    std::uint64_t old = 0;
    if (before) {
      while (j < before->size() && (*before)[j].first < upper) ++j;
      if (j < before->size() && (*before)[j].first == upper) old = (*before)[j].second;
    }
    if (count > old) out.emplace_back(upper, count - old);
  }
  return out;
}

std::uint64_t total(const Buckets& buckets) {
  std::uint64_t n = 0;
  for (const auto& b : buckets) n += b.second;
  return n;
}

// The bound under which `fraction` of the interval's calls fall, in microseconds.
double percentileUs(const Buckets& interval, std::uint64_t count, double fraction) {
  const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(fraction * static_cast<double>(count))));
  std::uint64_t seen = 0;
  for (const auto& [upper, n] : interval) {
    seen += n;
    if (seen >= rank) return static_cast<double>(upper) * 1e-3;
  }
  return static_cast<double>(interval.back().first) * 1e-3;
}

struct Interval {
  std::uint64_t calls = 0;
  std::optional<double> p50_us, p99_us;
};

Interval intervalOf(const std::vector<ServiceOverview::MethodLatency>& before,
                    const std::vector<ServiceOverview::MethodLatency>& now, rpc::Method method) {
  Interval out;
  const Buckets* current = bucketsOf(now, method);
  if (!current) return out;
  const Buckets delta = difference(*current, bucketsOf(before, method));
  out.calls = total(delta);
  if (out.calls > 0) {
    out.p50_us = percentileUs(delta, out.calls, 0.50);
    out.p99_us = percentileUs(delta, out.calls, 0.99);
  }
  return out;
}

double wallClockSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

HistoryPoint historyPoint(const std::vector<ServiceOverview::MethodLatency>& before,
                          const std::vector<ServiceOverview::MethodLatency>& now, double interval_seconds,
                          double unix_seconds) {
  HistoryPoint p;
  p.unix_seconds = unix_seconds;
  const double seconds = std::max(interval_seconds, 1e-3);
  for (const auto& m : now) {
    const Interval i = intervalOf(before, now, m.method);
    const double rate = static_cast<double>(i.calls) / seconds;
    if (m.method == rpc::Method::Evaluate) {
      p.evaluate_per_second = rate;
      p.evaluate_p50_us = i.p50_us;
      p.evaluate_p99_us = i.p99_us;
    } else if (m.method == rpc::Method::EvaluateBatch) {
      p.batch_per_second = rate;
      p.batch_p50_us = i.p50_us;
      p.batch_p99_us = i.p99_us;
    } else {
      p.other_per_second += rate;
    }
  }
  return p;
}

DashboardHistory::DashboardHistory(const Service& service, DashboardHistoryOptions options)
    : service_(service), options_(options), ring_(options.capacity) {
  if (options.interval.count() <= 0)
    throw std::invalid_argument("DashboardHistory: the sampling interval must be positive");
  thread_ = std::thread([this] { run(); });
}

DashboardHistory::~DashboardHistory() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

// Ticks on a fixed schedule (a slow sample does not shift the ones after it); each tick's
// point covers the time since the previous sample, as measured.
void DashboardHistory::run() {
  using Clock = std::chrono::steady_clock;
  auto before = service_.requestLatencies();
  auto before_at = Clock::now();
  auto next = before_at + options_.interval;
  std::unique_lock lock(mutex_);
  while (!wake_.wait_until(lock, next, [this] { return stopping_; })) {
    lock.unlock();
    auto now = service_.requestLatencies();
    const auto now_at = Clock::now();
    ring_.push(historyPoint(before, now, std::chrono::duration<double>(now_at - before_at).count(), wallClockSeconds()));
    before = std::move(now);
    before_at = now_at;
    next += options_.interval;
    if (next < now_at) next = now_at + options_.interval;  // fell behind (suspended): start afresh
    lock.lock();
  }
}

std::vector<HistoryPoint> DashboardHistory::points(double after_unix_seconds) const {
  return ring_.snapshotIf([after_unix_seconds](const HistoryPoint& p) { return p.unix_seconds > after_unix_seconds; });
}

std::string historyJson(const DashboardHistory& history, double after_unix_seconds) {
  using nlohmann::json;
  auto value = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  json out;
  out["interval_seconds"] = std::chrono::duration<double>(history.options().interval).count();
  out["capacity"] = history.options().capacity;
  out["points"] = json::array();
  for (const HistoryPoint& p : history.points(after_unix_seconds))
    out["points"].push_back({{"t", p.unix_seconds},
                             {"latency",
                              {{"Evaluate p50", value(p.evaluate_p50_us)},
                               {"Evaluate p99", value(p.evaluate_p99_us)},
                               {"EvaluateBatch p50", value(p.batch_p50_us)},
                               {"EvaluateBatch p99", value(p.batch_p99_us)}}},
                             {"rate",
                              {{"Evaluate", p.evaluate_per_second},
                               {"EvaluateBatch", p.batch_per_second},
                               {"other methods", p.other_per_second}}}});
  return out.dump();
}

}  // namespace robodiff::server
