#pragma once
// The service's figures (Service::metrics()) as a Prometheus text page for GET /metrics.
// Families (docs/service.md, "HTTP: metrics, probes, the dashboard"): robodiff_up, robodiff_serving_state{state},
// robodiff_uptime_seconds, robodiff_requests_total{method,status},
// robodiff_request_duration_seconds{method} (histogram), robodiff_transport_requests_total
// and _errors_total{transport}, robodiff_models_loaded, robodiff_functions_loaded,
// robodiff_functions_compiled, robodiff_builds{state}, robodiff_builds_failed_total,
// robodiff_specs_invalid_total, robodiff_cache_hits_total,
// robodiff_cache_misses_total, robodiff_cache_bytes, robodiff_cache_entries,
// robodiff_workers{state}, robodiff_request_queue_depth, robodiff_request_queue_capacity,
// robodiff_jobs{state}.

#include <string>

#include "robodiff/server/service.hpp"

namespace robodiff::server {

// The Content-Type of the page.
inline constexpr const char* kPrometheusContentType = "text/plain; version=0.0.4; charset=utf-8";

std::string serviceMetricsText(const ServiceMetrics& metrics);

}  // namespace robodiff::server
