#pragma once
// Noticing that robodiffd was paused (SIGSTOP, a frozen VM, starvation) long enough for
// RouDi to drop it. iceoryx 2.0's RouDi removes a process whose keep-alives stop for
// about 1.5 s and frees its ports' shared memory; the process is not told, and its next
// use of those ports fails on freed memory (POPO__CHUNK_LOCKING_ERROR, an abort). A
// thread that wakes every 100 ms sees such a pause as a gap in the monotonic clock.
#include <atomic>
#include <chrono>
#include <functional>
#include <thread>

namespace robodiff::server {

class PauseMonitor {
 public:
  // `on_pause(seconds)` runs once, on the monitor's thread, after the first gap longer
  // than `threshold`.
  PauseMonitor(std::chrono::milliseconds threshold, std::function<void(double seconds)> on_pause);
  ~PauseMonitor();
  PauseMonitor(const PauseMonitor&) = delete;
  PauseMonitor& operator=(const PauseMonitor&) = delete;

  bool tripped() const { return tripped_.load(); }

 private:
  void run();

  std::chrono::milliseconds threshold_;
  std::function<void(double)> on_pause_;
  std::atomic<bool> tripped_{false}, stopping_{false};
  std::thread thread_;
};

// Ends the process with `exit_code` if it is still alive `budget` from now: SIGTERM must
// never outlast the drain timeout, even when a transport's teardown hangs. Writes one
// JSON line to stderr first. Detached; nothing to undo.
void armShutdownWatchdog(std::chrono::milliseconds budget, int exit_code);

}  // namespace robodiff::server
