// What the worker pool keeps: a job, a worker serving jobs, a worker on its way out, and
// the pool's timing rules and how it words durations. Private to worker_pool.cpp.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdio>
#include <future>
#include <memory>
#include <string>

#include "robodiff/workers/worker_pool.hpp"
#include "robodiff/workers/worker_protocol.hpp"

namespace robodiff::workers::pool {

using Clock = std::chrono::steady_clock;

// How long a worker that closed its stdout (or was signalled) may take to exit before
// its tree is killed, and how long after that SIGKILL before it is given up on.
constexpr auto kExitGrace = std::chrono::seconds(1);
constexpr auto kKillGrace = std::chrono::seconds(5);
// Shutdown: idle workers get this long to leave on end of input before SIGTERM.
constexpr auto kEofGrace = std::chrono::milliseconds(250);
// A failed worker start is retried after this long; so is a start after a worker that
// exited by itself sooner than this after it started (a broken install would otherwise
// be restarted in a tight loop).
constexpr auto kSpawnRetry = std::chrono::seconds(1);

struct Job {
  JobId id = 0;
  std::string frame;  // the request as written to the worker ("id" and "limits" added)
  JobCallbacks callbacks;
  std::chrono::milliseconds timeout{0};
  std::promise<JobResult> promise;
  Clock::time_point submitted, started;
  pid_t worker_pid = 0;
  bool cancel_requested = false;
  bool finished = false;  // its result is decided (it may not be delivered yet)
};

struct Worker {
  pid_t pid = -1;
  int to_worker = -1;    // the worker's stdin: write end, non-blocking
  int from_worker = -1;  // the worker's stdout: read end, non-blocking
  FrameDecoder decoder;
  std::string unsent;    // bytes of the current request not written yet
  std::shared_ptr<Job> job;
  Clock::time_point deadline;
  Clock::time_point started;
  std::uint64_t jobs_done = 0;
};

// A worker on its way out: its stdout closed, or it was killed. Reaped without blocking.
struct Departing {
  pid_t pid = -1;
  std::shared_ptr<Job> job;  // the job it died during, completed once its status is known
  Clock::time_point kill_at;      // its tree is SIGKILLed if it has not exited by then
  Clock::time_point give_up_at;   // past this (after SIGKILL) it is reported and forgotten
  bool killed = false;
  bool young = false;  // left by itself within kSpawnRetry of its start
};

// "1 s", "1.5 s", "15 min"
inline std::string describeDuration(std::chrono::milliseconds d) {
  const auto ms = d.count();
  if (ms % 60000 == 0 && ms >= 60000) return std::to_string(ms / 60000) + " min";
  if (ms % 1000 == 0) return std::to_string(ms / 1000) + " s";
  char text[32];
  std::snprintf(text, sizeof text, "%.3g s", static_cast<double>(ms) / 1000.0);
  return text;
}

inline double secondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

}  // namespace robodiff::workers::pool
