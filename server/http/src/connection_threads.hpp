#pragma once
// httplib's task queue for robodiff: a thread per connection, at most `max` at once. When
// all are busy, enqueue() waits, so httplib's accept loop pauses and further clients wait
// in the listen backlog (no unbounded queue of accepted sockets holding descriptors).
#include <httplib.h>

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>

namespace robodiff::server {

class ConnectionThreads final : public httplib::TaskQueue {
 public:
  explicit ConnectionThreads(std::size_t max);
  // Runs `fn` (one connection) on a thread of its own once fewer than `max` run.
  void enqueue(std::function<void()> fn) override;
  // Waits for every connection's thread to finish.
  void shutdown() override;

 private:
  void finished();

  const std::size_t max_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::size_t running_ = 0;
};

}  // namespace robodiff::server
