// The robodiff-worker program's host: everything a worker process does for a WorkerPool
// (worker_pool.hpp) except the work of the layers above. It reads request frames on stdin
// and writes progress and result frames on stdout (worker_protocol.hpp), one request at a
// time, each under its "limits" (RLIMIT_AS), and answers "ping" and "build" itself. The
// program adds its own request types: batch/jobs' worker_main.cpp adds "batch" (batch
// jobs for the server's JobManager), so that workers/ never depends on batch/.
//
// stdout carries nothing but frames: it is moved to a private descriptor at startup and
// fd 1 points at stderr, so whatever a library prints cannot corrupt the stream. The
// worker dies with its pool (PR_SET_PDEATHSIG) and leaves when stdin ends. SIGPIPE keeps
// its default: a worker whose pool stopped listening has nothing left to do.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

namespace robodiff::workers {

// Sends one progress reply for the running request: {"id", "type": "progress"} plus
// `fields` (a JSON object, e.g. {"stage": "trace"} or {"fraction": 0.5, "message": ...}).
using ProgressSink = std::function<void(const nlohmann::json& fields)>;

// Runs one request: `envelope` is the whole request object ({"id", "type", "limits",
// "request", ...}); the answer is its result reply (workerResult / workerFailure). An
// exception becomes a failure of kind "internal" with its text.
using RequestHandler =
    std::function<nlohmann::json(std::uint64_t id, const nlohmann::json& envelope, const ProgressSink& progress)>;

// A request type a program adds to the host.
struct RequestType {
  std::string summary;  // one line for --help, e.g. "compiles a function into a library for the cache"
  RequestHandler handle;
};

// {"id": id, "type": "result", "ok": ok}: a handler adds its fields.
nlohmann::json workerResult(std::uint64_t id, bool ok);
// A failed result: "error_kind" (e.g. "invalid_request") and a "message" naming the problem.
nlohmann::json workerFailure(std::uint64_t id, const std::string& error_kind, const std::string& message);

// The worker program's main: checks the arguments (--help lists every request type),
// takes stdin/stdout and serves requests until stdin ends. `extra_types` are the types
// the program adds to "ping" and "build" (one with the same name replaces the host's).
// Returns the process's exit status: 0 at the end of input, 2 for bad arguments or a
// terminal on stdin, 3 when the frame stream breaks.
int runWorkerHost(int argc, char** argv, std::map<std::string, RequestType> extra_types);

}  // namespace robodiff::workers
