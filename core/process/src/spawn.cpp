#include "robodiff/process/spawn.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace robodiff::process {
namespace {

// The child's side: setup, exec, and on failure exec's errno into the report pipe.
[[noreturn]] void execChild(const char* path, char* const* argv, ChildSetup setup, const void* context,
                            int report_write, pid_t parent, int parent_death_signal) {
  if (parent_death_signal) {
    ::prctl(PR_SET_PDEATHSIG, parent_death_signal);
    if (::getppid() != parent) ::_exit(127);  // the parent died before prctl took effect
  }
  if (setup) setup(context, report_write);
  ::execv(path, argv);
  const int e = errno;
  (void)!::write(report_write, &e, sizeof e);
  ::_exit(127);
}

// The errno the child reported, or 0 when the pipe closed on a successful exec.
int readExecReport(int report_read) {
  int child_errno = 0;
  ssize_t got;
  do got = ::read(report_read, &child_errno, sizeof child_errno);
  while (got < 0 && errno == EINTR);
  return got == static_cast<ssize_t>(sizeof child_errno) ? child_errno : 0;
}

}  // namespace

Spawned spawn(const char* path, char* const* argv, ChildSetup setup, const void* context, int parent_death_signal) {
  int report[2];
  if (::pipe2(report, O_CLOEXEC) != 0) return {-1, std::string("pipe: ") + std::strerror(errno)};
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) execChild(path, argv, setup, context, report[1], parent, parent_death_signal);
  const int fork_errno = errno;
  ::close(report[1]);
  if (pid < 0) {
    ::close(report[0]);
    return {-1, std::string("fork: ") + std::strerror(fork_errno)};
  }
  const int exec_errno = readExecReport(report[0]);
  ::close(report[0]);
  if (exec_errno == 0) return {pid, {}};
  int status;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return {-1, "cannot execute '" + std::string(path) + "': " + std::strerror(exec_errno)};
}

}  // namespace robodiff::process
