#pragma once
// RouDi for robodiffd: use the machine's RouDi when one is running, otherwise start one
// owned by this process, configured with the pools of shm_mempools.hpp (= deploy/roudi.toml).
//
// The check is roudiRunning() (a connect() to RouDi's socket, microseconds): never the
// 60-second block of initRuntime() without a RouDi.
//
// "Embedded" RouDi: iceoryx's in-process RouDi (iceoryx_posh_roudi) needs <sys/acl.h>
// (libacl1-dev), which this platform does not install, so the owned RouDi is an
// `iox-roudi` child process (package iceoryx) with a generated config file. It is tied to
// this process: stopped (SIGKILL, then its leftovers removed) when the handle goes, and sent SIGTERM by
// the kernel if this process dies first (PR_SET_PDEATHSIG; call ensureRoudi from the main
// thread, since the signal follows the thread that started the child).

#include <memory>
#include <stdexcept>
#include <string_view>

#include "robodiff/server/log.hpp"

namespace robodiff::server {

enum class RoudiMode {
  Auto,      // the running RouDi, else an embedded one
  External,  // the running RouDi; none is an error
  Embedded,  // always start our own (an error when one is already running: one RouDi per host)
  Detached,  // the running RouDi, else start one that is left running when this process
             // exits (its own session; a restarted robodiffd uses it again, so the shm
             // clients registered with it survive the restart; iceoryx 2.0 clients cannot
             // move to a new RouDi). Stopping it is the operator's (its PID is logged).
};
// "auto" | "external" | "embedded" | "detached"; throws std::invalid_argument naming the value.
RoudiMode parseRoudiMode(std::string_view text);

// Which RouDi this process uses; an owned RouDi lives as long as its handle. Destroy
// the handle only after every iceoryx port of the process is gone (stop the ShmServer).
class RoudiHandle {
 public:
  virtual ~RoudiHandle() = default;
  virtual bool embedded() const = 0;
};

// Finds or starts RouDi per `mode` (a started one is waited for, up to 3 s, until it
// accepts runtimes) and logs which. Throws std::runtime_error with a clear message when
// the mode cannot be satisfied.
std::unique_ptr<RoudiHandle> ensureRoudi(RoudiMode mode, Logger& log);

}  // namespace robodiff::server
