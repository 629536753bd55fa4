// measured_cc: the compiler of both sides' cold builds, started from a small process so
// that its peak memory is its own.
//
// Linux's peak resident set of a process (wait4, getrusage) counts the pages it shares
// with its parent until exec, so a compiler forked by a process holding a tape or a
// trace reads at least that process's size. Both sides run this program as their
// compiler instead: it forks the real one (ANCHORS_REAL_CC) with the same arguments,
// waits, and appends "<peak KiB> <output file>" to ANCHORS_CC_LOG when set. The peak is
// wait4's, which takes in the driver's own children (cc1, as, ld). Exit status and
// output are the real compiler's.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

const char* outputArgument(int argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "-o") == 0) return argv[i + 1];
  return "-";
}

// One write of one short line, appended: lines of compilers running at once stay whole.
void appendPeak(const char* log, long kib, const char* output) {
  char line[4096];
  const int n = std::snprintf(line, sizeof line, "%ld %s\n", kib, output);
  if (n <= 0 || n >= static_cast<int>(sizeof line)) return;
  const int fd = open(log, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return;
  if (write(fd, line, static_cast<size_t>(n)) != n) std::fprintf(stderr, "measured_cc: cannot append to %s\n", log);
  close(fd);
}

}  // namespace

int main(int argc, char** argv) {
  const char* real = std::getenv("ANCHORS_REAL_CC");
  if (!real || !*real) {
    std::fprintf(stderr, "measured_cc: ANCHORS_REAL_CC (the compiler to run) is not set\n");
    return 127;
  }
  const pid_t pid = fork();
  if (pid < 0) {
    std::fprintf(stderr, "measured_cc: fork: %s\n", std::strerror(errno));
    return 127;
  }
  if (pid == 0) {
    argv[0] = const_cast<char*>(real);
    execv(real, argv);
    std::fprintf(stderr, "measured_cc: cannot run %s: %s\n", real, std::strerror(errno));
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  while (wait4(pid, &status, 0, &usage) < 0)
    if (errno != EINTR) return 127;
  if (const char* log = std::getenv("ANCHORS_CC_LOG"); log && *log) appendPeak(log, usage.ru_maxrss, outputArgument(argc, argv));
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}
