#include "worker_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "robodiff/process/program_path.hpp"
#include "robodiff/process/spawn.hpp"
#include "robodiff/workers/worker_pool.hpp"

namespace robodiff::workers {

namespace fs = std::filesystem;

namespace {

std::string signalName(int signal) {
  const char* abbrev = sigabbrev_np(signal);
  return abbrev ? std::string("SIG") + abbrev : "signal " + std::to_string(signal);
}

}  // namespace

std::string describeWorkerExit(pid_t pid, int status) {
  const std::string who = "worker " + std::to_string(pid);
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    return who + " was killed by signal " + std::to_string(sig) + " (" + signalName(sig) + ") during the job";
  }
  if (WIFEXITED(status))
    return who + " exited with status " + std::to_string(WEXITSTATUS(status)) + " during the job without a result";
  return who + " ended during the job";
}

namespace {

// What the forked worker sets up before exec (async-signal-safe calls only).
struct WorkerChild {
  long max_fd;
  int to_read;     // its stdin
  int from_write;  // its stdout
};

// Its own session (and process group), apart from the terminal's signals, so that every
// process it starts carries the session id even once orphaned (process_tree.hpp);
// default signal handling; stdin and stdout the pool's pipes, no other descriptor of the
// pool's process but `report_fd`.
void setUpWorker(const void* context, int report_fd) {
  const auto& c = *static_cast<const WorkerChild*>(context);
  sigset_t no_signals;
  sigemptyset(&no_signals);
  struct sigaction default_action {};
  default_action.sa_handler = SIG_DFL;
  ::setsid();
  for (int sig : {SIGPIPE, SIGINT, SIGTERM, SIGHUP, SIGQUIT}) ::sigaction(sig, &default_action, nullptr);
  ::sigprocmask(SIG_SETMASK, &no_signals, nullptr);  // the supervisor blocks SIGPIPE
  ::dup2(c.to_read, 0);
  ::dup2(c.from_write, 1);
  const auto keep = static_cast<unsigned>(report_fd);  // closes on exec
  if ((keep > 3 && ::close_range(3, keep - 1, 0) != 0) || ::close_range(keep + 1, ~0U, 0) != 0) {
    for (int fd = 3; fd < c.max_fd; ++fd)
      if (fd != report_fd) ::close(fd);
  }
}

// Two pipes (to the worker and from it), each end close-on-exec.
void openPipes(int to[2], int from[2]) {
  if (::pipe2(to, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  if (::pipe2(from, O_CLOEXEC) != 0) {
    const int e = errno;
    ::close(to[0]), ::close(to[1]);
    throw std::runtime_error(std::string("pipe: ") + std::strerror(e));
  }
}

}  // namespace

WorkerProcess startWorkerProcess(const fs::path& executable) {
  int to[2], from[2];
  openPipes(to, from);
  // Prepared before fork: in the child only async-signal-safe calls.
  const std::string path = executable.string();
  char* const argv[] = {const_cast<char*>(path.c_str()), nullptr};
  const long max_fd = std::min<long>(::sysconf(_SC_OPEN_MAX) > 0 ? ::sysconf(_SC_OPEN_MAX) : 1024, 65536);
  const WorkerChild setup{max_fd, to[0], from[1]};
  // SIGKILL when the pool's supervisor thread ends: a worker dies with its pool.
  const process::Spawned child = process::spawn(path.c_str(), argv, setUpWorker, &setup, SIGKILL);
  ::close(to[0]);
  ::close(from[1]);
  if (!child.ok()) {
    ::close(to[1]), ::close(from[0]);
    throw std::runtime_error("cannot start the worker: " + child.error);
  }
  return WorkerProcess{child.pid, to[1], from[0]};
}

fs::path defaultWorkerExecutable() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = self.parent_path() / "robodiff-worker";  // the build tree's bin/
    if (process::isExecutableFile(beside)) return beside;
    const fs::path installed = (self.parent_path() / ROBODIFF_WORKER_FROM_BINDIR / "robodiff-worker").lexically_normal();
    if (process::isExecutableFile(installed)) return installed;
  }
  const std::string in_path = process::findProgram("robodiff-worker");
  if (!in_path.empty()) return in_path;
  return {};
}

void setNonBlocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK); }

void closeFd(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

void consumePendingSigpipe() {
  sigset_t pipe_only;
  sigemptyset(&pipe_only);
  sigaddset(&pipe_only, SIGPIPE);
  const struct timespec zero {};
  while (::sigtimedwait(&pipe_only, nullptr, &zero) == SIGPIPE) {
  }
}

const char* toString(JobState state) {
  switch (state) {
    case JobState::Queued: return "queued";
    case JobState::Running: return "running";
    case JobState::Succeeded: return "succeeded";
    case JobState::Failed: return "failed";
    case JobState::Crashed: return "crashed";
    case JobState::TimedOut: return "timed out";
    case JobState::Cancelled: return "cancelled";
  }
  return "unknown";
}

}  // namespace robodiff::workers
