// The dashboard's routes: the page, its data and its history.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <optional>

#include "robodiff/server/dashboard.hpp"
#include "robodiff/server/dashboard_history.hpp"

namespace robodiff::server {
namespace {

HttpResponse jsonResponse(std::string body) {
  HttpResponse r;
  r.content_type = "application/json";
  r.body = std::move(body);
  r.headers.emplace_back("Cache-Control", "no-store");
  return r;
}

HttpResponse badRequest(std::string message) {
  HttpResponse r;
  r.status = 400;
  r.body = std::move(message) + "\n";
  return r;
}

// The value of `name` in an undecoded query ("after=1.5&x=y"); none when absent.
std::optional<std::string> queryValue(const std::string& query, const std::string& name) {
  std::size_t at = 0;
  while (at <= query.size()) {
    const std::size_t end = std::min(query.find('&', at), query.size());
    const std::string pair = query.substr(at, end - at);
    if (pair.rfind(name + "=", 0) == 0) return pair.substr(name.size() + 1);
    at = end + 1;
  }
  return std::nullopt;
}

// GET /api/history[?after=<unix seconds>]: the points after that time (all without it).
HttpResponse history(const DashboardHistory& h, const HttpRequest& request) {
  double after = -std::numeric_limits<double>::infinity();
  if (const std::optional<std::string> text = queryValue(request.query, "after")) {
    char* end = nullptr;
    errno = 0;
    after = std::strtod(text->c_str(), &end);
    if (text->empty() || end != text->c_str() + text->size() || errno != 0 || !std::isfinite(after))
      return badRequest("/api/history: after='" + text->substr(0, 40) +
                        "' is not a time in unix seconds (a finite number, e.g. after=1764135000.5)");
  }
  return jsonResponse(historyJson(h, after));
}

}  // namespace

void routeDashboard(HttpServer& server, const Service& service, DashboardHistoryOptions history_options) {
  auto page = [](const HttpRequest&) {
    HttpResponse r;
    r.content_type = "text/html; charset=utf-8";
    r.body = std::string(dashboardPage());
    r.headers.emplace_back("Cache-Control", "no-cache");
    return r;
  };
  server.route("/", page);
  server.route("/dashboard", page);
  server.route("/api/overview", [&service](const HttpRequest&) { return jsonResponse(overviewJson(service.overview())); });
  // The route owns the history: it samples for as long as the server holds its routes.
  auto h = std::make_shared<const DashboardHistory>(service, history_options);
  server.route("/api/history", [h](const HttpRequest& request) { return history(*h, request); });
}

}  // namespace robodiff::server
