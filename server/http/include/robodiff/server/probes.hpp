#pragma once
// Liveness and readiness for process supervisors and orchestrators (GET /healthz, /readyz).
//
// /healthz (liveness): 200 "ok" while the process answers at all, draining included
// ("ok (draining)"): a supervisor must not restart a server that is finishing its requests.
// /readyz (readiness): 200 when every check passes, else 503; the body has one line per
// check, "name: ok ..." or "name: failed (reason)", in the order the checks were added.
// Checks run on the HTTP thread at each request, so they must be quick (microseconds to
// a millisecond: a socket connect, a file created and removed).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "robodiff/server/http_server.hpp"

namespace robodiff::server {

struct ProbeResult {
  bool ok = true;
  std::string detail;  // ok: an optional note ("writable, 12.3 GiB free"); failed: the reason
};

class Probes {
 public:
  // The liveness answer's note (e.g. "draining"); unset: plain "ok".
  void setLivenessNote(std::function<std::string()> note);
  // A readiness check, reported as "name: ...".
  void addReadinessCheck(std::string name, std::function<ProbeResult()> check);

  HttpResponse liveness() const;
  HttpResponse readiness() const;
  // Routes /healthz and /readyz on `server` to this object (which must outlive it).
  void routeOn(HttpServer& server) const;

 private:
  struct Check {
    std::string name;
    std::function<ProbeResult()> run;
  };
  std::function<std::string()> liveness_note_;
  std::vector<Check> checks_;
};

// Whether `dir` takes new files: one is created there and removed (what the cache does
// when it stores a library), and at least `min_free_bytes` are free (statvfs, for
// unprivileged users).
ProbeResult checkDirectoryWritable(const std::filesystem::path& dir, std::uint64_t min_free_bytes);

}  // namespace robodiff::server
