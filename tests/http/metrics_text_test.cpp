// The Prometheus text writer: escaping, values, names; what it writes (and the service's
// whole page) parses as the text format with consistent histograms; and the validator
// itself rejects what is wrong.
#include <gtest/gtest.h>

#include <cmath>

#include "robodiff/server/metrics_text.hpp"
#include "robodiff/server/service_metrics_text.hpp"
#include "support/prometheus_text.hpp"

namespace robodiff::testing {
namespace {

using server::MetricsText;
using server::MetricType;

TEST(MetricsText, EscapesLabelValuesAndHelp) {
  EXPECT_EQ(MetricsText::escapeLabelValue("a\"b\\c\nd"), "a\\\"b\\\\c\\nd");
  EXPECT_EQ(MetricsText::escapeHelp("a \"quoted\" \\ help\nline"), "a \"quoted\" \\\\ help\\nline");

  MetricsText t;
  t.family("robodiff_test_total", MetricType::Counter, "Help with \\ and\na newline.");
  t.sample("robodiff_test_total", {{"path", "C:\\dir \"x\"\nnext"}}, 3);
  const PromText parsed = parsePrometheusText(t.text());
  ASSERT_TRUE(parsed.errors.empty()) << parsed.errorText() << t.text();
  EXPECT_EQ(parsed.value("robodiff_test_total", {{"path", "C:\\dir \"x\"\nnext"}}), 3.0);
  EXPECT_EQ(parsed.family("robodiff_test_total")->type, "counter");
}

TEST(MetricsText, FormatsValues) {
  EXPECT_EQ(MetricsText::formatValue(0), "0");
  EXPECT_EQ(MetricsText::formatValue(42), "42");
  EXPECT_EQ(MetricsText::formatValue(-7), "-7");
  EXPECT_EQ(MetricsText::formatValue(0.25), "0.25");
  EXPECT_EQ(MetricsText::formatValue(5e-6), "5e-06");
  EXPECT_EQ(MetricsText::formatValue(HUGE_VAL), "+Inf");
  EXPECT_EQ(MetricsText::formatValue(-HUGE_VAL), "-Inf");
  EXPECT_EQ(MetricsText::formatValue(std::nan("")), "NaN");
  EXPECT_EQ(MetricsText::formatValue(1e300), "1e+300");
}

TEST(MetricsText, RefusesBadNames) {
  MetricsText t;
  EXPECT_THROW(t.family("1abc", MetricType::Gauge, ""), std::invalid_argument);
  EXPECT_THROW(t.family("a-b", MetricType::Gauge, ""), std::invalid_argument);
  EXPECT_THROW(t.sample("ok", {{"bad-label", "x"}}, 1), std::invalid_argument);
  EXPECT_THROW(t.sample("ok", {{"__reserved", "x"}}, 1), std::invalid_argument);
  EXPECT_TRUE(MetricsText::validMetricName("ns:sub_total"));
  EXPECT_FALSE(MetricsText::validLabelName("ns:sub"));
}

TEST(MetricsText, HistogramIsCumulativeEndingInInfEqualToCount) {
  MetricsText t;
  t.family("robodiff_latency_seconds", MetricType::Histogram, "Latency.");
  const std::vector<double> bounds = {0.001, 0.01, 0.1};
  const std::vector<std::uint64_t> counts = {2, 5, 9};
  t.histogram("robodiff_latency_seconds", {{"method", "Evaluate"}}, bounds, counts, 10, 0.75);
  t.histogram("robodiff_latency_seconds", {{"method", "Health"}}, bounds, std::vector<std::uint64_t>{0, 0, 0}, 0, 0);
  const PromText p = parsePrometheusText(t.text());
  ASSERT_TRUE(p.errors.empty()) << p.errorText() << t.text();
  EXPECT_EQ(p.value("robodiff_latency_seconds_bucket", {{"method", "Evaluate"}, {"le", "0.01"}}), 5.0);
  EXPECT_EQ(p.value("robodiff_latency_seconds_bucket", {{"method", "Evaluate"}, {"le", "+Inf"}}), 10.0);
  EXPECT_EQ(p.value("robodiff_latency_seconds_count", {{"method", "Evaluate"}}), 10.0);
  EXPECT_EQ(p.value("robodiff_latency_seconds_sum", {{"method", "Evaluate"}}), 0.75);
  EXPECT_EQ(p.family("robodiff_latency_seconds")->samples.size(), 2u * (4 + 2));
}

TEST(PrometheusValidator, RejectsWhatIsWrong) {
  auto errors = [](const std::string& text) { return parsePrometheusText(text).errors.size(); };
  EXPECT_EQ(errors("# TYPE a counter\na 1\n"), 0u);
  EXPECT_GT(errors("# TYPE a counter\na 1"), 0u);                          // no final newline
  EXPECT_GT(errors("# TYPE a counter\na{x=\"1} 1\n"), 0u);                 // unterminated value
  EXPECT_GT(errors("# TYPE a counter\na{x=\"\\q\"} 1\n"), 0u);             // bad escape
  EXPECT_GT(errors("# TYPE a counter\na one\n"), 0u);                      // bad value
  EXPECT_GT(errors("# TYPE a counter\na 1\na 2\n"), 0u);                   // series twice
  EXPECT_GT(errors("# TYPE a counter\na 1\n# TYPE b gauge\nb 1\na{x=\"y\"} 1\n"), 0u);  // not contiguous
  EXPECT_GT(errors("a 1\n# TYPE a counter\n"), 0u);                        // TYPE after samples
  EXPECT_GT(errors("# TYPE a countre\n"), 0u);                             // unknown type
  const std::string h = "# TYPE h histogram\n";
  EXPECT_EQ(errors(h + "h_bucket{le=\"1\"} 1\nh_bucket{le=\"+Inf\"} 2\nh_sum 3\nh_count 2\n"), 0u);
  EXPECT_GT(errors(h + "h_bucket{le=\"1\"} 3\nh_bucket{le=\"+Inf\"} 2\nh_sum 3\nh_count 2\n"), 0u);  // not cumulative
  EXPECT_GT(errors(h + "h_bucket{le=\"1\"} 1\nh_sum 3\nh_count 2\n"), 0u);                          // no +Inf
  EXPECT_GT(errors(h + "h_bucket{le=\"1\"} 1\nh_bucket{le=\"+Inf\"} 2\nh_sum 3\nh_count 5\n"), 0u);  // +Inf != count
  EXPECT_GT(errors(h + "h_bucket{le=\"1\"} 1\nh_bucket{le=\"+Inf\"} 2\nh_count 2\n"), 0u);           // no sum
}

// The service's page from a hand-made snapshot: every family there, valid, with the numbers given.
TEST(ServiceMetricsText, RendersEveryFamilyValidly) {
  server::ServiceMetrics m;
  m.state = rpc::ServingState::Serving;
  m.uptime_seconds = 12.5;
  m.latency_bounds_seconds = {1e-5, 1e-4, 1e-3};
  for (std::uint32_t i = 0; i < rpc::kMethodCount; ++i) {
    server::ServiceMetrics::MethodFigures f;
    f.method = static_cast<rpc::Method>(i);
    f.replies = {{StatusCode::Ok, i}};
    f.latency_buckets = {0, 0, i};
    f.latency_count = i;
    f.latency_sum_seconds = 1e-4 * i;
    m.methods.push_back(f);
  }
  m.methods[2].replies.emplace_back(StatusCode::InvalidArgument, 4);
  m.methods[2].latency_count += 4;
  m.transports = {{"iceoryx", 10, 1}, {"dds", 5, 0}};
  m.builds_queued = 1;
  m.builds_done = 3;
  m.cache_hits = 7;
  m.cache_misses = 2;
  m.cache_bytes = 123456;
  m.cache_entries = 3;
  m.workers_total = 2;
  m.workers_busy = 1;
  m.queue_depth = 4;
  m.queue_capacity = 256;
  m.jobs_enabled = true;
  m.jobs.succeeded = 2;

  const std::string text = server::serviceMetricsText(m);
  const PromText p = parsePrometheusText(text);
  ASSERT_TRUE(p.errors.empty()) << p.errorText() << text;
  for (const char* family :
       {"robodiff_up", "robodiff_serving_state", "robodiff_uptime_seconds", "robodiff_requests_total",
        "robodiff_request_duration_seconds", "robodiff_transport_requests_total", "robodiff_transport_errors_total",
        "robodiff_models_loaded", "robodiff_functions_loaded", "robodiff_functions_compiled", "robodiff_builds",
        "robodiff_cache_hits_total", "robodiff_cache_misses_total", "robodiff_cache_bytes", "robodiff_cache_entries",
        "robodiff_workers", "robodiff_request_queue_depth", "robodiff_request_queue_capacity", "robodiff_jobs"}) {
    const PromFamily* f = p.family(family);
    ASSERT_NE(f, nullptr) << family << " missing\n" << text;
    EXPECT_FALSE(f->help.empty()) << family;
    EXPECT_NE(f->type, "untyped") << family;
  }
  EXPECT_EQ(p.value("robodiff_up"), 1.0);
  EXPECT_EQ(p.value("robodiff_serving_state", {{"state", "serving"}}), 1.0);
  EXPECT_EQ(p.value("robodiff_serving_state", {{"state", "draining"}}), 0.0);
  EXPECT_EQ(p.value("robodiff_requests_total", {{"method", "Evaluate"}, {"status", "OK"}}), 2.0);
  EXPECT_EQ(p.value("robodiff_requests_total", {{"method", "Evaluate"}, {"status", "INVALID_ARGUMENT"}}), 4.0);
  EXPECT_EQ(p.value("robodiff_request_duration_seconds_count", {{"method", "Evaluate"}}), 6.0);
  EXPECT_EQ(p.value("robodiff_transport_errors_total", {{"transport", "iceoryx"}}), 1.0);
  EXPECT_EQ(p.value("robodiff_builds", {{"state", "done"}}), 3.0);
  EXPECT_EQ(p.value("robodiff_cache_bytes"), 123456.0);
  EXPECT_EQ(p.value("robodiff_workers", {{"state", "idle"}}), 1.0);
  EXPECT_EQ(p.value("robodiff_request_queue_depth"), 4.0);
  EXPECT_EQ(p.value("robodiff_jobs", {{"state", "succeeded"}}), 2.0);
  EXPECT_EQ(p.family("robodiff_requests_total")->type, "counter");
  EXPECT_EQ(p.family("robodiff_request_duration_seconds")->type, "histogram");
}

}  // namespace
}  // namespace robodiff::testing
