// Starting a program in a forked child, with its failure to execute reported back.
//
// The child runs the caller's setup (its descriptors, limits, signals, process group)
// and then execs; if exec fails, its errno comes back through a close-on-exec pipe, so
// the caller learns "cannot execute '/usr/bin/cc': Permission denied" at once instead of
// an exit status it cannot tell from the program's own.
#pragma once

#include <sys/types.h>

#include <string>

namespace robodiff::process {

// What the forked child does before exec. Only async-signal-safe calls (the parent may
// have other threads; nothing may allocate). `report_fd` must stay open until exec (it
// closes on exec by itself): a setup that closes descriptors spares it.
using ChildSetup = void (*)(const void* context, int report_fd);

struct Spawned {
  pid_t pid = -1;     // the running child; -1 when it did not start
  std::string error;  // why not: "pipe: ...", "fork: ..." or "cannot execute '<path>': ..."
  bool ok() const { return pid > 0; }
};

// Forks; with a `parent_death_signal`, the child gets it when the thread that forked it
// ends (PR_SET_PDEATHSIG; a child whose parent is already gone exits at once); then it
// runs setup(context, report_fd) when a setup is given and execv(path, argv) (argv
// null-terminated; this process's environment). Returns once the child has executed
// the program, or has been reaped after failing to.
Spawned spawn(const char* path, char* const* argv, ChildSetup setup = nullptr, const void* context = nullptr,
              int parent_death_signal = 0);

}  // namespace robodiff::process
