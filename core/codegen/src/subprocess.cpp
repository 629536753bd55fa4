#include "subprocess.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "robodiff/process/program_path.hpp"
#include "robodiff/process/spawn.hpp"

namespace robodiff::codegen::detail {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kOutputCap = 256 * 1024;

struct Running {
  std::size_t index;
  pid_t pid;
  int fd;  // read end of the stdout/stderr pipe; -1 once at end of file
  Clock::time_point started;
};

// A failure to start, as `outcome` says it; returns pid -1.
pid_t cannotStart(ProcessOutcome& outcome, std::string why) {
  outcome.state = ProcessOutcome::State::CannotStart;
  outcome.start_error = std::move(why);
  return -1;
}

// What the forked compiler's child sets up before exec (async-signal-safe calls only).
struct CompilerChild {
  const struct rlimit* as_limit;  // null: no limit
  int devnull;                    // stdin; -1: left as it is
  int out_write;                  // stdout and stderr
};

// Its own process group (killed with the thread that waits for it: spawn's death
// signal), `as_limit`'s address space, stdin from /dev/null, stdout and stderr into the output pipe.
void setUpChild(const void* context, int /*report_fd*/) {
  const auto& c = *static_cast<const CompilerChild*>(context);
  setpgid(0, 0);  // its own group: a timeout kills the compiler's children too
  if (c.as_limit) setrlimit(RLIMIT_AS, c.as_limit);
  if (c.devnull >= 0) dup2(c.devnull, 0);
  dup2(c.out_write, 1);
  dup2(c.out_write, 2);
}

// Starts one process; on failure fills outcome and returns pid -1.
pid_t start(const std::vector<std::string>& argv, const ProcessLimits& limits, int* out_fd, ProcessOutcome& outcome) {
  const std::string path = process::findProgram(argv.at(0));
  if (path.empty()) return cannotStart(outcome, process::whyNotFound(argv[0]));
  // Everything the child needs is prepared before fork.
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  int out[2];
  if (pipe2(out, O_CLOEXEC) != 0) return cannotStart(outcome, std::string("pipe: ") + std::strerror(errno));
  const int devnull = open("/dev/null", O_RDONLY | O_CLOEXEC);
  struct rlimit as_limit;
  as_limit.rlim_cur = as_limit.rlim_max = static_cast<rlim_t>(limits.address_space_bytes);
  const CompilerChild setup{limits.address_space_bytes > 0 ? &as_limit : nullptr, devnull, out[1]};
  // SIGKILL when the thread waiting for it ends: a compiler does not outlive its build.
  const process::Spawned child = process::spawn(path.c_str(), args.data(), setUpChild, &setup, SIGKILL);
  if (devnull >= 0) close(devnull);
  close(out[1]);
  if (!child.ok()) {
    close(out[0]);
    return cannotStart(outcome, child.error);
  }
  fcntl(out[0], F_SETFL, fcntl(out[0], F_GETFL) | O_NONBLOCK);
  *out_fd = out[0];
  return child.pid;
}

void drain(Running& r, ProcessOutcome& o) {
  char buf[8192];
  while (r.fd >= 0) {
    ssize_t n = read(r.fd, buf, sizeof buf);
    if (n > 0) {
      if (o.output.size() < kOutputCap) o.output.append(buf, std::min<std::size_t>(n, kOutputCap - o.output.size()));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n == 0) {
      close(r.fd);
      r.fd = -1;
    }
    return;  // EAGAIN: nothing more for now
  }
}

// Waits for a process; `block`: wait even if it has not ended. Returns whether reaped.
bool reap(Running& r, ProcessOutcome& o, bool block) {
  int status = 0;
  struct rusage usage {};
  pid_t got;
  do got = wait4(r.pid, &status, block ? 0 : WNOHANG, &usage);
  while (got < 0 && errno == EINTR);
  if (got != r.pid) return false;
  o.seconds = std::chrono::duration<double>(Clock::now() - r.started).count();
  o.peak_rss_bytes = static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;  // Linux: KiB
  if (WIFEXITED(status)) {
    o.state = ProcessOutcome::State::Exited;
    o.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    o.state = ProcessOutcome::State::Signaled;
    o.signal = WTERMSIG(status);
  }
  // Leftover children of the process (its group) do not outlive it.
  killpg(r.pid, SIGKILL);
  drain(r, o);
  if (r.fd >= 0) {
    close(r.fd);
    r.fd = -1;
  }
  return true;
}

}  // namespace

std::string commandLine(const std::vector<std::string>& argv) {
  std::string s;
  for (const auto& a : argv) {
    if (!s.empty()) s += ' ';
    const bool plain = !a.empty() && a.find_first_of(" \t\n'\"\\$`*?;&|<>()") == std::string::npos;
    if (plain) {
      s += a;
    } else {
      s += '\'';
      for (char c : a) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
      s += '\'';
    }
  }
  return s;
}

std::vector<ProcessOutcome> runProcesses(const std::vector<std::vector<std::string>>& commands,
                                         const ProcessLimits& limits) {
  std::vector<ProcessOutcome> outcomes(commands.size());
  std::vector<Running> running;
  std::size_t next = 0;
  bool failed = false;
  const unsigned jobs = std::max(1u, limits.jobs);

  auto killAll = [&](ProcessOutcome::State why) {
    for (Running& r : running) {
      killpg(r.pid, SIGKILL);
      reap(r, outcomes[r.index], true);
      outcomes[r.index].state = why;
    }
    running.clear();
  };

  while (true) {
    while (!failed && next < commands.size() && running.size() < jobs) {
      if (Clock::now() >= limits.deadline) break;
      Running r{next, -1, -1, Clock::now()};
      r.pid = start(commands[next], limits, &r.fd, outcomes[next]);
      ++next;
      if (r.pid < 0) {
        failed = true;
        break;
      }
      running.push_back(r);
    }
    if (failed) killAll(ProcessOutcome::State::Cancelled);
    if (running.empty()) break;

    const auto now = Clock::now();
    if (now >= limits.deadline) {
      killAll(ProcessOutcome::State::TimedOut);
      break;
    }
    // Wait for output or the deadline; check for exits at least every 20 ms (a process
    // may end while a child of it still holds the pipe), every 1 ms once a process has
    // closed its output (it is about to exit).
    std::vector<pollfd> fds;
    for (const Running& r : running)
      if (r.fd >= 0) fds.push_back({r.fd, POLLIN, 0});
    const bool exiting = fds.size() < running.size();
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(limits.deadline - now).count();
    const int timeout_ms = static_cast<int>(std::min<long long>(std::max<long long>(left, 1), exiting ? 1 : 20));
    if (!fds.empty()) poll(fds.data(), fds.size(), timeout_ms);
    else usleep(static_cast<useconds_t>(timeout_ms) * 1000);

    for (std::size_t i = 0; i < running.size();) {
      Running& r = running[i];
      ProcessOutcome& o = outcomes[r.index];
      drain(r, o);
      if (reap(r, o, false)) {
        if (!o.ok()) failed = true;
        running.erase(running.begin() + static_cast<std::ptrdiff_t>(i));
      } else {
        ++i;
      }
    }
  }
  // Commands never started because of the deadline are timed out, after a failure cancelled.
  for (std::size_t i = next; i < commands.size(); ++i)
    outcomes[i].state = failed ? ProcessOutcome::State::Cancelled : ProcessOutcome::State::TimedOut;
  return outcomes;
}

}  // namespace robodiff::codegen::detail
