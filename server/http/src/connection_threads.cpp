#include "connection_threads.hpp"

#include <algorithm>
#include <system_error>
#include <thread>

namespace robodiff::server {

ConnectionThreads::ConnectionThreads(std::size_t max) : max_(std::max<std::size_t>(max, 1)) {}

void ConnectionThreads::enqueue(std::function<void()> fn) {
  {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return running_ < max_; });
    ++running_;
  }
  auto run = [this, fn = std::move(fn)] {
    fn();
    finished();
  };
  try {
    std::thread(run).detach();  // a copy: `run` stays whole if no thread can be had
  } catch (const std::system_error&) {
    run();  // no thread to be had: serve it on the accept thread
  }
}

void ConnectionThreads::finished() {
  // Notified under the lock: once shutdown() sees zero, no thread touches this object again.
  std::lock_guard lock(mutex_);
  --running_;
  changed_.notify_all();
}

void ConnectionThreads::shutdown() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return running_ == 0; });
}

}  // namespace robodiff::server
