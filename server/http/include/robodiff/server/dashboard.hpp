#pragma once
// The operators' dashboard: one page (GET / and /dashboard; HTML, CSS and script in one
// file, server/http/dashboard/dashboard.html, compiled in) that polls GET /api/overview
// every second and redraws: models, functions with their compile state and latency, the
// build queue and failed builds, the cache, the workers, jobs with progress bars, and
// latency and request-rate charts drawn from the fine histograms' differences.

#include <string>
#include <string_view>

#include "robodiff/server/http_server.hpp"
#include "robodiff/server/service.hpp"

namespace robodiff::server {

// The page, as compiled in.
std::string_view dashboardPage();

// Service::overview() as the JSON the page reads (field by field in docs/service.md,
// "The dashboard"). Times in seconds, latencies in microseconds.
std::string overviewJson(const ServiceOverview& overview);

// Routes /, /dashboard (the page) and /api/overview on `server`; `service` outlives it.
void routeDashboard(HttpServer& server, const Service& service);

}  // namespace robodiff::server
