#pragma once
// A writer of the Prometheus text exposition format (version 0.0.4): for each metric
// family a "# HELP" and a "# TYPE" line, then its samples `name{label="value",...} value`.
// HELP text escapes '\' and newline; label values escape '\', '"' and newline. Metric and
// label names are checked (a bad one is a programming error: std::invalid_argument).
// Values are printed exactly for integers, shortest round-trip otherwise, +Inf/-Inf/NaN.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace robodiff::server {

using MetricLabels = std::vector<std::pair<std::string, std::string>>;

enum class MetricType { Counter, Gauge, Histogram, Untyped };

class MetricsText {
 public:
  // Starts a family: its HELP and TYPE lines. Counters are named with their "_total".
  void family(std::string_view name, MetricType type, std::string_view help);
  // One sample of the current family (`name` may carry a suffix: _bucket, _sum, _count).
  void sample(std::string_view name, const MetricLabels& labels, double value);
  // A histogram's samples: cumulative bucket counts per upper bound (ascending), the +Inf
  // bucket (= count), _sum and _count; `labels` go on each, `le` is added to buckets.
  void histogram(std::string_view name, const MetricLabels& labels, std::span<const double> bounds,
                 std::span<const std::uint64_t> cumulative, std::uint64_t count, double sum);

  const std::string& text() const { return text_; }

  static std::string escapeHelp(std::string_view help);
  static std::string escapeLabelValue(std::string_view value);
  static std::string formatValue(double value);
  static bool validMetricName(std::string_view name);  // [a-zA-Z_:][a-zA-Z0-9_:]*
  static bool validLabelName(std::string_view name);   // [a-zA-Z_][a-zA-Z0-9_]*, not "__..."

 private:
  std::string text_;
};

}  // namespace robodiff::server
