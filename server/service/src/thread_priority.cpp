#include "thread_priority.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>

namespace robodiff::server::detail {

bool lowerCallingThreadPriority(unsigned increment) {
  if (increment == 0) return true;
  // On Linux a thread id names one thread to setpriority (POSIX would say the process).
  const id_t tid = static_cast<id_t>(::syscall(SYS_gettid));
  errno = 0;
  const int current = ::getpriority(PRIO_PROCESS, tid);
  if (current == -1 && errno != 0) return false;
  const int wanted = current + static_cast<int>(increment) > 19 ? 19 : current + static_cast<int>(increment);
  return ::setpriority(PRIO_PROCESS, tid, wanted) == 0;
}

}  // namespace robodiff::server::detail
