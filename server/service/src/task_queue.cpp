#include "task_queue.hpp"

#include <algorithm>
#include <exception>

#include "thread_priority.hpp"

namespace robodiff::server::detail {

TaskQueue::TaskQueue(std::string name, unsigned threads, std::size_t capacity, ErrorHandler on_error, unsigned nice)
    : name_(std::move(name)), capacity_(capacity), on_error_(std::move(on_error)) {
  const unsigned n = std::max(1u, threads);
  threads_.reserve(n);
  for (unsigned i = 0; i < n; ++i)
    threads_.emplace_back([this, nice] {
      lowerCallingThreadPriority(nice);
      loop();
    });
}

TaskQueue::~TaskQueue() { stop(); }

bool TaskQueue::post(Task task) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return false;
    if (capacity_ != 0 && tasks_.size() >= capacity_) return false;
    tasks_.push_back(std::move(task));
  }
  wake_.notify_one();
  return true;
}

void TaskQueue::stop(bool run_queued) {
  std::deque<Task> dropped;  // destroyed outside the lock: a task's captures may do anything
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    if (!run_queued) dropped.swap(tasks_);
  }
  wake_.notify_all();
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
}

std::size_t TaskQueue::depth() const {
  std::lock_guard lock(mutex_);
  return tasks_.size();
}

std::size_t TaskQueue::running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

bool TaskQueue::idle() const {
  std::lock_guard lock(mutex_);
  return tasks_.empty() && running_ == 0;
}

void TaskQueue::loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
    if (tasks_.empty()) return;  // stopping and nothing left to run
    Task task = std::move(tasks_.front());
    tasks_.pop_front();
    ++running_;
    lock.unlock();
    try {
      task();
    } catch (const std::exception& e) {
      if (on_error_) on_error_(name_ + ": a task failed: " + e.what());
    } catch (...) {
      if (on_error_) on_error_(name_ + ": a task failed with an unknown exception");
    }
    task = nullptr;  // its captures go before the task counts as done
    lock.lock();
    --running_;
  }
}

}  // namespace robodiff::server::detail
