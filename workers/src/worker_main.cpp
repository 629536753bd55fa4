// robodiff-worker: runs build jobs and batch jobs for a WorkerPool (worker_pool.hpp), one
// at a time.
//
// Requests come as frames on stdin, replies go as frames on stdout (worker_protocol.hpp).
// stdout carries nothing else: it is moved to a private descriptor at startup and fd 1
// points at stderr, so whatever a library prints cannot corrupt the stream. The worker
// dies with its pool (PR_SET_PDEATHSIG) and leaves when stdin ends. SIGPIPE keeps its
// default: a worker whose pool stopped listening has nothing left to do.
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "robodiff/batch/batch_job.hpp"
#include "robodiff/workers/build_job.hpp"
#include "robodiff/workers/worker_protocol.hpp"

namespace {

using nlohmann::json;
using namespace robodiff::workers;

constexpr const char* kHelp =
    "robodiff-worker: builds compiled functions for robodiff's worker pool.\n"
    "\n"
    "It is started by the pool (robodiff warmup, the server), not by people: it reads\n"
    "build requests as length-prefixed JSON frames on stdin and writes progress and\n"
    "results as frames on stdout, until stdin ends.\n"
    "\n"
    "Usage: robodiff-worker [--help]\n";

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

json result(std::uint64_t id, bool ok) { return {{"id", id}, {"type", "result"}, {"ok", ok}}; }

json failure(std::uint64_t id, const std::string& kind, const std::string& message) {
  json r = result(id, false);
  r["error_kind"] = kind;
  r["message"] = message;
  return r;
}

// RLIMIT_AS for the duration of one job (soft limit only, so it can be restored).
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

json runBuild(const Channels& c, std::uint64_t id, const json& envelope) {
  const auto request_it = envelope.find("request");
  if (request_it == envelope.end() || !request_it->is_object())
    return failure(id, "invalid_request", "a build request needs a \"request\" object");
  BuildRequest request;
  try {
    request = buildRequestFromJson(request_it->dump());
  } catch (const std::invalid_argument& e) {
    return failure(id, "invalid_request", e.what());
  }
  const BuildOutcome outcome = executeBuild(request, [&](const std::string& stage) {
    reply(c, {{"id", id}, {"type", "progress"}, {"stage", stage}});
  });
  json r = json::parse(toJson(outcome));
  r["id"] = id;
  r["type"] = "result";
  return r;
}

// A batch job (batch/jobs: trajectory, identify, trajopt): {"request": {"kind", "params",
// "result_dir", "cache_dir"}}. Progress goes out as {"fraction", "message"}; the result
// is {"ok": true, "result": {...}} or a failure naming the problem.
json runBatch(const Channels& c, std::uint64_t id, const json& envelope) {
  const auto request = envelope.find("request");
  if (request == envelope.end() || !request->is_object())
    return failure(id, "invalid_request", "a batch request needs a \"request\" object");
  robodiff::batch::BatchJobContext context;
  context.result_dir = request->value("result_dir", std::string());
  context.cache_dir = request->value("cache_dir", std::string());
  // A service's job reads only under the directories it sends (absent: the caller runs
  // the worker as itself, and the job reads anywhere).
  if (const auto dirs = request->find("readable_dirs"); dirs != request->end()) {
    if (!dirs->is_array()) return failure(id, "invalid_request", "\"readable_dirs\" must be an array of paths");
    std::vector<std::filesystem::path> readable;
    for (const json& d : *dirs)
      if (d.is_string()) readable.emplace_back(d.get<std::string>());
    context.files = robodiff::batch::FileAccess::under(std::move(readable));
  }
  context.progress = [&](double fraction, const std::string& message) {
    reply(c, {{"id", id}, {"type", "progress"}, {"fraction", fraction}, {"message", message}});
  };
  if (context.result_dir.empty()) return failure(id, "invalid_request", "a batch request needs a \"result_dir\"");
  try {
    const json params = request->value("params", json::object());
    json r = result(id, true);
    r["result"] = robodiff::batch::runBatchJob(request->value("kind", std::string()), params, context);
    return r;
  } catch (const robodiff::batch::JobParamsError& e) {
    return failure(id, "invalid_params", e.what());
  } catch (const std::bad_alloc&) {
    return failure(id, "memory", "the job ran out of memory (the job's limit: see the server's job memory setting)");
  } catch (const std::exception& e) {
    return failure(id, "failed", e.what());
  }
}

// The job's "limits": {"memory_bytes": B}; 0 when absent.
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

// One request to its result, under the request's memory limit.
json handle(const Channels& c, const std::string& frame) {
  const json envelope = json::parse(frame, nullptr, false);
  if (!envelope.is_object()) throw ProtocolError("a request that is not a JSON object: " + frame.substr(0, 200));
  const auto id_it = envelope.find("id");
  if (id_it == envelope.end() || !id_it->is_number_unsigned())
    throw ProtocolError("a request without a numeric \"id\": " + frame.substr(0, 200));
  const auto id = id_it->get<std::uint64_t>();
  const std::string type = envelope.value("type", std::string());
  const AddressSpaceLimit limit(memoryLimitOf(envelope));
  if (type == "ping") {  // also says which limit a job runs under
    json r = result(id, true);
    r["pid"] = ::getpid();
    r["address_space_limit_bytes"] = currentAddressSpaceLimit();
    return r;
  }
  if (type == "build") return runBuild(c, id, envelope);
  if (type == "batch") return runBatch(c, id, envelope);
  return failure(id, "invalid_request", "unknown request type \"" + type + "\" (this worker knows: build, batch, ping)");
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(kHelp, stdout);
      return 0;
    }
    std::fprintf(stderr, "robodiff-worker: unknown argument '%s'\n\n%s", arg.c_str(), kHelp);
    return 2;
  }
  if (::isatty(0)) {
    std::fprintf(stderr, "%s\nstdin is a terminal: this program is started by robodiff's worker pool.\n", kHelp);
    return 2;
  }
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // the pool sets it too; this covers other parents
  const Channels channels = takeChannels();

  try {
    while (const std::optional<std::string> frame = readFrame(channels.requests)) {
      json answer;
      try {
        answer = handle(channels, *frame);
      } catch (const ProtocolError&) {
        throw;
      } catch (const std::exception& e) {
        // Only what handle() cannot attribute to a job's id reaches this point as a
        // ProtocolError; anything else still answers the job.
        const json envelope = json::parse(*frame, nullptr, false);
        answer = failure(envelope.value("id", std::uint64_t{0}), "internal", e.what());
      }
      reply(channels, answer);
    }
  } catch (const ProtocolError& e) {
    std::fprintf(stderr, "robodiff-worker %d: %s\n", static_cast<int>(::getpid()), e.what());
    return 3;
  }
  return 0;  // end of input: the pool is done with this worker
}
