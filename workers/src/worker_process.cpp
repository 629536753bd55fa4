#include "worker_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "robodiff/workers/worker_pool.hpp"

namespace robodiff::workers {

namespace fs = std::filesystem;

namespace {

std::string signalName(int signal) {
  const char* abbrev = sigabbrev_np(signal);
  return abbrev ? std::string("SIG") + abbrev : "signal " + std::to_string(signal);
}

}  // namespace

bool isExecutableFile(const fs::path& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

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

// The forked worker: its own session (and process group), apart from the terminal's
// signals, so that every process it starts carries the session id even once orphaned
// (process_tree.hpp); killed with the pool's supervisor thread; default signal handling;
// stdin and stdout the pool's pipes, no other descriptor of the pool's process but
// `report_write`, where a failed exec's errno goes. Only async-signal-safe calls (the
// pool has other threads).
[[noreturn]] void execWorker(const char* path, char* const* argv, pid_t parent, long max_fd, int to_read,
                             int from_write, int report_write) {
  sigset_t no_signals;
  sigemptyset(&no_signals);
  struct sigaction default_action {};
  default_action.sa_handler = SIG_DFL;
  ::setsid();
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // dies with the pool's supervisor thread
  if (::getppid() != parent) ::_exit(127);  // the pool died before prctl took effect
  for (int sig : {SIGPIPE, SIGINT, SIGTERM, SIGHUP, SIGQUIT}) ::sigaction(sig, &default_action, nullptr);
  ::sigprocmask(SIG_SETMASK, &no_signals, nullptr);  // the supervisor blocks SIGPIPE
  ::dup2(to_read, 0);
  ::dup2(from_write, 1);
  const auto keep = static_cast<unsigned>(report_write);  // closes on exec
  if ((keep > 3 && ::close_range(3, keep - 1, 0) != 0) || ::close_range(keep + 1, ~0U, 0) != 0) {
    for (int fd = 3; fd < max_fd; ++fd)
      if (fd != report_write) ::close(fd);
  }
  ::execv(path, argv);
  const int e = errno;
  (void)!::write(report_write, &e, sizeof e);
  ::_exit(127);
}

// Three pipes (to the worker, from it, and its exec report), each end close-on-exec.
void openPipes(int to[2], int from[2], int report[2]) {
  if (::pipe2(to, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  if (::pipe2(from, O_CLOEXEC) != 0) {
    const int e = errno;
    ::close(to[0]), ::close(to[1]);
    throw std::runtime_error(std::string("pipe: ") + std::strerror(e));
  }
  if (::pipe2(report, O_CLOEXEC) != 0) {
    const int e = errno;
    ::close(to[0]), ::close(to[1]), ::close(from[0]), ::close(from[1]);
    throw std::runtime_error(std::string("pipe: ") + std::strerror(e));
  }
}

}  // namespace

WorkerProcess startWorkerProcess(const fs::path& executable) {
  int to[2], from[2], report[2];
  openPipes(to, from, report);
  // Prepared before fork: in the child only async-signal-safe calls.
  const std::string path = executable.string();
  char* const argv[] = {const_cast<char*>(path.c_str()), nullptr};
  const pid_t parent = ::getpid();
  const long max_fd = std::min<long>(::sysconf(_SC_OPEN_MAX) > 0 ? ::sysconf(_SC_OPEN_MAX) : 1024, 65536);
  const pid_t pid = ::fork();
  if (pid == 0) execWorker(path.c_str(), argv, parent, max_fd, to[0], from[1], report[1]);
  const int fork_errno = errno;
  ::close(to[0]);
  ::close(from[1]);
  ::close(report[1]);
  if (pid < 0) {
    ::close(to[1]), ::close(from[0]), ::close(report[0]);
    throw std::runtime_error("cannot start " + path + ": fork: " + std::strerror(fork_errno));
  }
  // The report pipe closes on a successful exec or carries exec's errno.
  int exec_errno = 0;
  ssize_t got;
  do got = ::read(report[0], &exec_errno, sizeof exec_errno);
  while (got < 0 && errno == EINTR);
  ::close(report[0]);
  if (got == static_cast<ssize_t>(sizeof exec_errno)) {
    int status;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    ::close(to[1]), ::close(from[0]);
    throw std::runtime_error("cannot execute " + path + ": " + std::strerror(exec_errno));
  }
  return WorkerProcess{pid, to[1], from[0]};
}

fs::path defaultWorkerExecutable() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = self.parent_path() / "robodiff-worker";  // the build tree's bin/
    if (isExecutableFile(beside)) return beside;
    const fs::path installed = (self.parent_path() / ROBODIFF_WORKER_FROM_BINDIR / "robodiff-worker").lexically_normal();
    if (isExecutableFile(installed)) return installed;
  }
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = dirs.substr(start, end - start);
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / "robodiff-worker";
    if (isExecutableFile(candidate)) return candidate;
    start = end + 1;
  }
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
