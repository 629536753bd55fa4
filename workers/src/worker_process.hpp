// Starting one robodiff-worker process, its pipes, and describing how it and its jobs ended.
//
// The worker leads its own session (so everything it starts can be found and killed,
// orphans included), dies with the thread that started it (PR_SET_PDEATHSIG), gets the
// default dispositions of the terminal signals, and inherits nothing of the caller but
// its stdin and stdout pipes.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>

// Where `cmake --install` puts robodiff-worker, relative to the installed programs
// (workers/CMakeLists.txt defines it from GNUInstallDirs: ../libexec/robodiff by default).
#ifndef ROBODIFF_WORKER_FROM_BINDIR
#define ROBODIFF_WORKER_FROM_BINDIR "../libexec/robodiff"
#endif

namespace robodiff::workers {

struct WorkerProcess {
  pid_t pid = -1;
  int to_worker = -1;    // the worker's stdin (write end)
  int from_worker = -1;  // the worker's stdout (read end)
};

// Forks and executes `executable`. Throws std::runtime_error naming the program and the
// reason when it cannot be started or executed.
WorkerProcess startWorkerProcess(const std::filesystem::path& executable);

// "worker 123 was killed by signal 9 (SIGKILL) during the job", or its exit status.
std::string describeWorkerExit(pid_t pid, int status);

// The pipes to and from a worker.
void setNonBlocking(int fd);
void closeFd(int& fd);  // closes it (when open) and marks it closed (-1)
// The SIGPIPE a write to a dead worker raised (blocked in the writing thread) is taken off.
void consumePendingSigpipe();

}  // namespace robodiff::workers
