#pragma once
// The process-wide iceoryx runtime, shared by the iceoryx server and client.
//
// iceoryx allows one runtime per process (PoshRuntime::initRuntime registers the process
// with RouDi once), so a process that serves and calls over iceoryx must share it: every
// iceoryx user in robodiff calls ensureRuntime() first.
//
// initRuntime() with no RouDi running blocks for 60 s and then aborts the process, so
// ensureRuntime() first checks that RouDi is there (roudiRunning(): a connect() to its
// UNIX domain socket, microseconds) and answers UNAVAILABLE at once when it is not.

#include <string>
#include <string_view>

#include "robodiff/schema/status.hpp"

namespace robodiff::shm {

// Where iceoryx 2.0 RouDi listens for runtimes: the UNIX datagram socket /tmp/roudi.
std::string roudiSocketPath();

// True when a live RouDi is bound to its socket. A socket file left behind by a RouDi
// that died refuses the connection, so a stale file reads as "not running".
bool roudiRunning();

// After a RouDi was killed (SIGKILL: a RouDi stopped with SIGINT sends SIGTERM to every
// process still registered with it, and hangs if a crashed process left a port's mutex
// locked): removes its socket and shared memory, unless a RouDi runs again meanwhile.
void removeRoudiLeftovers();

// Sets iceoryx's own log level to warnings and errors (its default is verbose). Called by
// ensureRuntime(); callable before embedding a RouDi.
void quietIceoryxLogs();

// Registers this process with RouDi, once; later calls return OK at once. UNAVAILABLE
// (without blocking) when no RouDi is running. The runtime's name is
// "<prefix>-<pid>-<random>" (unique per process, as RouDi requires).
Status ensureRuntime(std::string_view name_prefix = "robodiff");

// Whether ensureRuntime() has succeeded in this process.
bool runtimeReady();

}  // namespace robodiff::shm
