// The Prometheus text format writer.
#include "robodiff/server/metrics_text.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace robodiff::server {
namespace {

bool nameChar(char c, bool first, bool colon) {
  const bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || (colon && c == ':');
  return alpha || (!first && c >= '0' && c <= '9');
}

const char* typeName(MetricType type) {
  switch (type) {
    case MetricType::Counter: return "counter";
    case MetricType::Gauge: return "gauge";
    case MetricType::Histogram: return "histogram";
    case MetricType::Untyped: break;
  }
  return "untyped";
}

}  // namespace

bool MetricsText::validMetricName(std::string_view name) {
  if (name.empty()) return false;
  for (std::size_t i = 0; i < name.size(); ++i)
    if (!nameChar(name[i], i == 0, true)) return false;
  return true;
}

bool MetricsText::validLabelName(std::string_view name) {
  if (name.empty() || name.starts_with("__")) return false;  // reserved for Prometheus itself
  for (std::size_t i = 0; i < name.size(); ++i)
    if (!nameChar(name[i], i == 0, false)) return false;
  return true;
}

std::string MetricsText::escapeHelp(std::string_view help) {
  std::string out;
  for (const char c : help) {
    if (c == '\\') out += "\\\\";
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

std::string MetricsText::escapeLabelValue(std::string_view value) {
  std::string out;
  for (const char c : value) {
    if (c == '\\') out += "\\\\";
    else if (c == '"') out += "\\\"";
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

std::string MetricsText::formatValue(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
  if (value == std::trunc(value) && std::abs(value) < 9.007199254740992e15)  // 2^53: exact as an integer
    return std::to_string(static_cast<long long>(value));
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);  // shortest round-trip
  return std::string(buffer, end);
}

void MetricsText::family(std::string_view name, MetricType type, std::string_view help) {
  if (!validMetricName(name)) throw std::invalid_argument("invalid metric name '" + std::string(name) + "'");
  text_ += "# HELP " + std::string(name) + " " + escapeHelp(help) + "\n";
  text_ += "# TYPE " + std::string(name) + " " + typeName(type) + "\n";
}

void MetricsText::sample(std::string_view name, const MetricLabels& labels, double value) {
  if (!validMetricName(name)) throw std::invalid_argument("invalid metric name '" + std::string(name) + "'");
  text_ += name;
  if (!labels.empty()) {
    text_ += '{';
    for (std::size_t i = 0; i < labels.size(); ++i) {
      if (!validLabelName(labels[i].first))
        throw std::invalid_argument("invalid label name '" + labels[i].first + "' on " + std::string(name));
      text_ += (i == 0 ? "" : ",") + labels[i].first + "=\"" + escapeLabelValue(labels[i].second) + "\"";
    }
    text_ += '}';
  }
  text_ += " " + formatValue(value) + "\n";
}

void MetricsText::histogram(std::string_view name, const MetricLabels& labels, std::span<const double> bounds,
                            std::span<const std::uint64_t> cumulative, std::uint64_t count, double sum) {
  if (bounds.size() != cumulative.size())
    throw std::invalid_argument("histogram " + std::string(name) + ": bounds and counts differ in number");
  const std::string base(name);
  MetricLabels with_le = labels;
  with_le.emplace_back("le", "");
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    with_le.back().second = formatValue(bounds[i]);
    sample(base + "_bucket", with_le, static_cast<double>(cumulative[i]));
  }
  with_le.back().second = "+Inf";
  sample(base + "_bucket", with_le, static_cast<double>(count));
  sample(base + "_sum", labels, sum);
  sample(base + "_count", labels, static_cast<double>(count));
}

}  // namespace robodiff::server
