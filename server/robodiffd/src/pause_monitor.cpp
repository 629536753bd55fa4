#include "pause_monitor.hpp"

#include <unistd.h>

#include <cstdio>

namespace robodiff::server {

PauseMonitor::PauseMonitor(std::chrono::milliseconds threshold, std::function<void(double seconds)> on_pause)
    : threshold_(threshold), on_pause_(std::move(on_pause)), thread_([this] { run(); }) {}

PauseMonitor::~PauseMonitor() {
  stopping_ = true;
  thread_.join();
}

void PauseMonitor::run() {
  using Clock = std::chrono::steady_clock;
  constexpr auto kTick = std::chrono::milliseconds(100);
  auto last = Clock::now();
  while (!stopping_) {
    std::this_thread::sleep_for(kTick);
    const auto now = Clock::now();
    const auto gap = now - last;
    last = now;
    if (gap > threshold_ && !tripped_.exchange(true))
      on_pause_(std::chrono::duration<double>(gap).count());
  }
}

void armShutdownWatchdog(std::chrono::milliseconds budget, int exit_code) {
  std::thread([budget, exit_code] {
    std::this_thread::sleep_for(budget);
    std::fprintf(stderr,
                 "{\"level\":\"error\",\"event\":\"shutdown_overrun\",\"message\":\"robodiffd did not stop within "
                 "%.1f s of the signal; exiting now\"}\n",
                 std::chrono::duration<double>(budget).count());
    std::fflush(stderr);
    ::_exit(exit_code);
  }).detach();
}

}  // namespace robodiff::server
