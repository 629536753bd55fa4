#pragma once
// The operators' dashboard: one page (GET / and /dashboard; HTML, CSS and script in one
// file, server/http/dashboard/dashboard.html, compiled in) that polls GET /api/overview
// every second and redraws: models, functions with their compile state and latency, the
// build queue, failed builds and invalid specs, the cache, the workers, the fleet (a build
// or robot host's counts and build hosts; hidden when standalone), jobs with progress
// bars, and latency and request-rate charts drawn from GET /api/history (the server's
// recent history, dashboard_history.hpp: the charts are full from the moment it opens).

#include <string>
#include <string_view>

#include "robodiff/server/dashboard_history.hpp"
#include "robodiff/server/http_server.hpp"
#include "robodiff/server/service.hpp"

namespace robodiff::server {

// The page, as compiled in.
std::string_view dashboardPage();

// Service::overview() as the JSON the page reads (field by field in docs/service.md,
// "The dashboard"). Times in seconds, latencies in microseconds.
std::string overviewJson(const ServiceOverview& overview);

// Routes /, /dashboard (the page), /api/overview and /api/history on `server`, and starts
// the history's sampling (it stops when `server` is destroyed); `service` outlives `server`.
void routeDashboard(HttpServer& server, const Service& service, DashboardHistoryOptions history = {});

}  // namespace robodiff::server
