// Killing a process with everything it started.
//
// A worker's compilers run in process groups of their own (so that the compiler driver
// can kill its children), so killing the worker's group is not enough: descendants are
// found through the parent links in /proc/<pid>/stat, and, when the root leads a session
// of its own (workers do: setsid), through the session id, which stays with orphans whose
// parent links were cut when their parent died. The root is stopped first (SIGSTOP) so
// that it cannot start more while its tree is collected; each descendant found is
// stopped too, and the collection repeats until no new one appears; then every
// descendant's process group and the descendant itself get SIGKILL, then the root.
// A root that has exited but is not reaped yet (a zombie) still holds its pid and
// session id: killing its tree then sweeps what it left behind.
#pragma once

#include <sys/types.h>

#include <optional>
#include <vector>

namespace robodiff::workers::detail {

struct ProcessStat {
  pid_t pid = 0, ppid = 0, pgid = 0, sid = 0;
  char state = '?';  // R, S, D, T, Z, ...
};

// /proc/<pid>/stat, or nullopt when the process does not exist (any more).
std::optional<ProcessStat> readProcessStat(pid_t pid);

// Every live process whose parent chain leads to `root`, or whose session `root` leads
// (root excluded), found in one pass over /proc.
std::vector<pid_t> descendantsOf(pid_t root);

// Stops `root`, collects and stops its descendants until no new one appears, then
// SIGKILLs their process groups (never the caller's own group), them, and the root's
// group and the root. Returns the descendants killed. The root is not reaped: it is the
// caller's child (or someone's), for its parent to wait for.
std::vector<pid_t> killProcessTree(pid_t root);

}  // namespace robodiff::workers::detail
