#pragma once
// A fixed set of threads running tasks from a queue, optionally bounded: the request
// threads (bounded: a full queue is refused, the transport replies RESOURCE_EXHAUSTED)
// and the build stages (unbounded: every new function gets its trace and its compile).
// A task that throws is reported to `on_error` and never ends its thread.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace robodiff::server::detail {

class TaskQueue {
 public:
  using Task = std::function<void()>;
  using ErrorHandler = std::function<void(const std::string& what)>;

  // `capacity` tasks may wait (0: no bound); `threads` run them (at least 1), each
  // `nice` nicer than the thread that made the queue (thread_priority.hpp).
  TaskQueue(std::string name, unsigned threads, std::size_t capacity, ErrorHandler on_error = {},
            unsigned nice = 0);
  ~TaskQueue();  // stop(): runs what is queued, then joins
  TaskQueue(const TaskQueue&) = delete;
  TaskQueue& operator=(const TaskQueue&) = delete;

  // False when the queue is full or stopping; the task is then not run.
  bool post(Task task);
  // Stops accepting tasks; runs those queued (or drops them when !run_queued), joins the
  // threads. Idempotent.
  void stop(bool run_queued = true);

  std::size_t depth() const;    // waiting, not running
  std::size_t running() const;  // being run now
  bool idle() const;            // nothing waiting and nothing running
  std::size_t capacity() const { return capacity_; }
  unsigned threads() const { return static_cast<unsigned>(threads_.size()); }

 private:
  void loop();

  std::string name_;
  std::size_t capacity_;
  ErrorHandler on_error_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Task> tasks_;
  std::size_t running_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace robodiff::server::detail
