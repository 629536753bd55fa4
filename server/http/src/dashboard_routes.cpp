// The dashboard's routes: the page and its data.
#include "robodiff/server/dashboard.hpp"

namespace robodiff::server {

void routeDashboard(HttpServer& server, const Service& service) {
  auto page = [](const HttpRequest&) {
    HttpResponse r;
    r.content_type = "text/html; charset=utf-8";
    r.body = std::string(dashboardPage());
    r.headers.emplace_back("Cache-Control", "no-cache");
    return r;
  };
  server.route("/", page);
  server.route("/dashboard", page);
  server.route("/api/overview", [&service](const HttpRequest&) {
    HttpResponse r;
    r.content_type = "application/json";
    r.body = overviewJson(service.overview());
    r.headers.emplace_back("Cache-Control", "no-store");
    return r;
  });
}

}  // namespace robodiff::server
