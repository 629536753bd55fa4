// runWorkerHost: the worker program's frame loop, its "ping" and "build" requests, and the
// per-request memory limit (worker_host.hpp).
#include "robodiff/workers/worker_host.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "robodiff/workers/build_job.hpp"
#include "robodiff/workers/worker_protocol.hpp"

namespace robodiff::workers {

using nlohmann::json;

json workerResult(std::uint64_t id, bool ok) { return {{"id", id}, {"type", "result"}, {"ok", ok}}; }

json workerFailure(std::uint64_t id, const std::string& error_kind, const std::string& message) {
  json r = workerResult(id, false);
  r["error_kind"] = error_kind;
  r["message"] = message;
  return r;
}

// Named, not anonymous: unity builds put this file in one translation unit with others.
namespace worker_host_detail {

using RequestTypes = std::map<std::string, RequestType>;

struct Channels {
  int requests = -1;  // the pool's requests (was fd 0)
  int replies = -1;   // the pool's replies (was fd 1)
};

// Moves stdin and stdout out of the way of everything else in the process and its
// children: fd 0 reads /dev/null, fd 1 writes to stderr.
Channels takeChannels() {
  Channels c;
  c.requests = ::fcntl(0, F_DUPFD_CLOEXEC, 3);
  c.replies = ::fcntl(1, F_DUPFD_CLOEXEC, 3);
  if (c.requests < 0 || c.replies < 0) {
    std::fprintf(stderr, "robodiff-worker: cannot take stdin/stdout: %s\n", std::strerror(errno));
    std::exit(3);
  }
  const int devnull = ::open("/dev/null", O_RDONLY);
  if (devnull >= 0) {
    ::dup2(devnull, 0);
    if (devnull != 0) ::close(devnull);
  }
  ::dup2(2, 1);
  return c;
}

void reply(const Channels& c, const json& message) { writeFrame(c.replies, message.dump()); }

// RLIMIT_AS for the duration of one request (soft limit only, so it can be restored).
class AddressSpaceLimit {
 public:
  explicit AddressSpaceLimit(std::uint64_t bytes) {
    if (bytes == 0 || ::getrlimit(RLIMIT_AS, &saved_) != 0) return;
    struct rlimit limited = saved_;
    limited.rlim_cur = static_cast<rlim_t>(bytes);
    if (saved_.rlim_max != RLIM_INFINITY && limited.rlim_cur > saved_.rlim_max) limited.rlim_cur = saved_.rlim_max;
    active_ = ::setrlimit(RLIMIT_AS, &limited) == 0;
    if (!active_) std::fprintf(stderr, "robodiff-worker: cannot set RLIMIT_AS: %s\n", std::strerror(errno));
  }
  ~AddressSpaceLimit() {
    if (active_) ::setrlimit(RLIMIT_AS, &saved_);
  }
  AddressSpaceLimit(const AddressSpaceLimit&) = delete;
  AddressSpaceLimit& operator=(const AddressSpaceLimit&) = delete;

 private:
  struct rlimit saved_ {};
  bool active_ = false;
};

// The request's "limits": {"memory_bytes": B}; 0 when absent.
std::uint64_t memoryLimitOf(const json& envelope) {
  const auto limits = envelope.find("limits");
  if (limits == envelope.end() || !limits->is_object()) return 0;
  const auto bytes = limits->find("memory_bytes");
  return bytes != limits->end() && bytes->is_number_unsigned() ? bytes->get<std::uint64_t>() : 0;
}

// This process's RLIMIT_AS soft limit; 0: none.
std::uint64_t currentAddressSpaceLimit() {
  struct rlimit now {};
  if (::getrlimit(RLIMIT_AS, &now) != 0 || now.rlim_cur == RLIM_INFINITY) return 0;
  return static_cast<std::uint64_t>(now.rlim_cur);
}

// A health check that also says which limit a request runs under.
json runPing(std::uint64_t id, const json&, const ProgressSink&) {
  json r = workerResult(id, true);
  r["pid"] = ::getpid();
  r["address_space_limit_bytes"] = currentAddressSpaceLimit();
  return r;
}

// {"request": BuildRequest}: compiles one function (build_job.hpp); progress names each stage.
json runBuild(std::uint64_t id, const json& envelope, const ProgressSink& progress) {
  const auto request_it = envelope.find("request");
  if (request_it == envelope.end() || !request_it->is_object())
    return workerFailure(id, "invalid_request", "a build request needs a \"request\" object");
  BuildRequest request;
  try {
    request = buildRequestFromJson(request_it->dump());
  } catch (const std::invalid_argument& e) {
    return workerFailure(id, "invalid_request", e.what());
  }
  const BuildOutcome outcome = executeBuild(request, [&](const std::string& stage) { progress({{"stage", stage}}); });
  json r = json::parse(toJson(outcome));
  r["id"] = id;
  r["type"] = "result";
  return r;
}

RequestTypes allRequestTypes(RequestTypes extra) {
  RequestTypes types = std::move(extra);
  types.try_emplace("ping", RequestType{"a health check (answers with its pid and memory limit)", runPing});
  types.try_emplace("build", RequestType{"compiles a function into a library for the cache", runBuild});
  return types;
}

std::string knownTypeNames(const RequestTypes& types) {
  std::string names;
  for (const auto& [name, type] : types) names += (names.empty() ? "" : ", ") + name;
  return names;
}

std::string helpText(const RequestTypes& types) {
  std::string help =
      "robodiff-worker: runs jobs for robodiff's worker pool, one at a time.\n"
      "\n"
      "It is started by the pool (robodiff warmup, the server's builds and jobs), not by\n"
      "people: it reads requests as length-prefixed JSON frames on stdin and writes progress\n"
      "and results as frames on stdout, until stdin ends. The requests it runs:\n";
  for (const auto& [name, type] : types) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-7s %s\n", name.c_str(), type.summary.c_str());
    help += line;
  }
  return help + "\nUsage: robodiff-worker [--help]\n";
}

// One request to its result, under the request's memory limit.
json handle(const Channels& c, const RequestTypes& types, const std::string& frame) {
  const json envelope = json::parse(frame, nullptr, false);
  if (!envelope.is_object()) throw ProtocolError("a request that is not a JSON object: " + frame.substr(0, 200));
  const auto id_it = envelope.find("id");
  if (id_it == envelope.end() || !id_it->is_number_unsigned())
    throw ProtocolError("a request without a numeric \"id\": " + frame.substr(0, 200));
  const auto id = id_it->get<std::uint64_t>();
  const std::string type = envelope.value("type", std::string());
  const auto known = types.find(type);
  if (known == types.end())
    return workerFailure(id, "invalid_request",
                         "unknown request type \"" + type + "\" (this worker knows: " + knownTypeNames(types) + ")");
  const AddressSpaceLimit limit(memoryLimitOf(envelope));
  const ProgressSink progress = [&](const json& fields) {
    json message = {{"id", id}, {"type", "progress"}};
    message.update(fields);
    reply(c, message);
  };
  return known->second.handle(id, envelope, progress);
}

// Answers requests until stdin ends (0) or the stream breaks (3).
int serve(const Channels& channels, const RequestTypes& types) {
  try {
    while (const std::optional<std::string> frame = readFrame(channels.requests)) {
      json answer;
      try {
        answer = handle(channels, types, *frame);
      } catch (const ProtocolError&) {
        throw;
      } catch (const std::exception& e) {
        // Only what handle() cannot attribute to a request's id reaches this point as a
        // ProtocolError; anything else still answers the request.
        const json envelope = json::parse(*frame, nullptr, false);
        answer = workerFailure(envelope.value("id", std::uint64_t{0}), "internal", e.what());
      }
      reply(channels, answer);
    }
  } catch (const ProtocolError& e) {
    std::fprintf(stderr, "robodiff-worker %d: %s\n", static_cast<int>(::getpid()), e.what());
    return 3;
  }
  return 0;  // end of input: the pool is done with this worker
}

}  // namespace worker_host_detail

int runWorkerHost(int argc, char** argv, std::map<std::string, RequestType> extra_types) {
  using namespace worker_host_detail;
  const RequestTypes types = allRequestTypes(std::move(extra_types));
  const std::string help = helpText(types);
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(help.c_str(), stdout);
      return 0;
    }
    std::fprintf(stderr, "robodiff-worker: unknown argument '%s'\n\n%s", arg.c_str(), help.c_str());
    return 2;
  }
  if (::isatty(0)) {
    std::fprintf(stderr, "%s\nstdin is a terminal: this program is started by robodiff's worker pool.\n",
                 help.c_str());
    return 2;
  }
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // the pool sets it too; this covers other parents
  return serve(takeChannels(), types);
}

}  // namespace robodiff::workers
