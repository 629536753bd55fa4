// The probes: the answers of /healthz and /readyz, and the cache directory's check.
#include "robodiff/server/probes.hpp"

#include <fcntl.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace robodiff::server {
namespace {

std::string gib(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f GiB", static_cast<double>(bytes) / (1024.0 * 1024 * 1024));
  return text;
}

}  // namespace

void Probes::setLivenessNote(std::function<std::string()> note) { liveness_note_ = std::move(note); }

void Probes::addReadinessCheck(std::string name, std::function<ProbeResult()> check) {
  checks_.push_back({std::move(name), std::move(check)});
}

HttpResponse Probes::liveness() const {
  HttpResponse r;
  const std::string note = liveness_note_ ? liveness_note_() : std::string();
  r.body = note.empty() ? "ok\n" : "ok (" + note + ")\n";
  return r;
}

HttpResponse Probes::readiness() const {
  HttpResponse r;
  bool all = true;
  for (const Check& c : checks_) {
    ProbeResult result;
    try {
      result = c.run();
    } catch (const std::exception& e) {
      result = {false, std::string("check threw: ") + e.what()};
    }
    all = all && result.ok;
    if (result.ok) r.body += c.name + ": ok" + (result.detail.empty() ? "" : " (" + result.detail + ")") + "\n";
    else r.body += c.name + ": failed (" + result.detail + ")\n";
  }
  r.status = all ? 200 : 503;
  return r;
}

void Probes::routeOn(HttpServer& server) const {
  server.route("/healthz", [this](const HttpRequest&) { return liveness(); });
  server.route("/readyz", [this](const HttpRequest&) { return readiness(); });
}

ProbeResult checkDirectoryWritable(const std::filesystem::path& dir, std::uint64_t min_free_bytes) {
  std::string name = (dir / ".robodiff-ready-XXXXXX").string();
  const int fd = ::mkstemp(name.data());
  if (fd < 0) return {false, "cannot create a file in " + dir.string() + ": " + std::strerror(errno)};
  ::close(fd);
  ::unlink(name.c_str());
  struct statvfs fs{};
  if (::statvfs(dir.c_str(), &fs) != 0) return {false, "statvfs " + dir.string() + ": " + std::strerror(errno)};
  const std::uint64_t free_bytes = static_cast<std::uint64_t>(fs.f_bavail) * fs.f_frsize;
  if (free_bytes < min_free_bytes)
    return {false, dir.string() + " has " + gib(free_bytes) + " free, below " + gib(min_free_bytes)};
  return {true, "writable, " + gib(free_bytes) + " free"};
}

}  // namespace robodiff::server
