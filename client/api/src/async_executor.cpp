// AsyncExecutor: see async_executor.hpp.
#include "async_executor.hpp"

#include <pthread.h>

#include <algorithm>
#include <memory>
#include <new>
#include <optional>
#include <string>

namespace robodiff::client::detail {

BlockPool::BlockPool(std::size_t blocks)
    : arena_(std::make_unique<std::byte[]>(blocks * kBlockSize)), blocks_(blocks) {
  free_.reserve(blocks);
  for (std::size_t i = blocks; i-- > 0;) free_.push_back(arena_.get() + i * kBlockSize);
}

bool BlockPool::owns(const void* p) const {
  const auto* b = static_cast<const std::byte*>(p);
  return b >= arena_.get() && b < arena_.get() + blocks_ * kBlockSize;
}

void* BlockPool::allocate(std::size_t bytes) {
  if (bytes <= kBlockSize) {
    std::lock_guard lock(mutex_);
    if (!free_.empty()) {
      void* p = free_.back();
      free_.pop_back();
      return p;
    }
    ++fallbacks_;
  } else {
    std::lock_guard lock(mutex_);
    ++fallbacks_;
  }
  return ::operator new(bytes);
}

void BlockPool::deallocate(void* p, std::size_t bytes) noexcept {
  if (owns(p)) {
    std::lock_guard lock(mutex_);
    free_.push_back(p);  // never beyond the reserved capacity: each block is pushed once
    return;
  }
  ::operator delete(p, bytes);
}

std::size_t BlockPool::fallbacks() const {
  std::lock_guard lock(mutex_);
  return fallbacks_;
}

namespace {

struct Call {
  Function function;  // a copy: keeps the function (and its client) alive until done
  std::span<const double> inputs;
  std::span<double> outputs;
  std::promise<Status> promise;
};

}  // namespace

struct AsyncExecutor::Shared {
  std::shared_ptr<BlockPool> pool;
  std::mutex mutex;
  std::condition_variable wake;
  std::vector<std::optional<Call>> ring;  // capacity slots, head..head+count used
  std::size_t head = 0, count = 0;
  bool stopping = false;

  void run() {
    for (;;) {
      std::optional<Call> call;
      {
        std::unique_lock lock(mutex);
        wake.wait(lock, [&] { return stopping || count > 0; });
        if (count == 0) return;  // stopping, nothing left
        call = std::move(ring[head]);
        ring[head].reset();
        head = (head + 1) % ring.size();
        --count;
      }
      call->promise.set_value(call->function.evaluate(call->inputs, call->outputs));
      call.reset();  // may drop the last reference to the Client (see the header)
    }
  }
};

AsyncExecutor::AsyncExecutor(std::size_t threads, std::size_t capacity) : shared_(std::make_shared<Shared>()) {
  capacity = std::max<std::size_t>(capacity, 1);
  // Two blocks per future (its state and its result) for every call queued, running, or
  // finished but not yet collected by its caller; twice that to leave room for futures a
  // caller holds on to.
  shared_->pool = std::make_shared<BlockPool>(4 * capacity + 8);
  shared_->ring.resize(capacity);
  threads = std::max<std::size_t>(threads, 1);
  for (std::size_t i = 0; i < threads; ++i)
    threads_.emplace_back([shared = shared_] {
      ::pthread_setname_np(::pthread_self(), "robodiff-async");  // in ps, gdb and perf
      shared->run();
    });
}

AsyncExecutor::~AsyncExecutor() {
  {
    std::lock_guard lock(shared_->mutex);
    shared_->stopping = true;
  }
  shared_->wake.notify_all();
  for (std::thread& t : threads_) {
    if (t.get_id() == std::this_thread::get_id())
      t.detach();  // this thread dropped the last reference; it leaves its loop by itself
    else
      t.join();
  }
}

std::future<Status> AsyncExecutor::submit(const Function& function, std::span<const double> inputs,
                                          std::span<double> outputs) {
  std::promise<Status> promise(std::allocator_arg, PoolAllocator<char>(shared_->pool));
  std::future<Status> future = promise.get_future();
  {
    std::unique_lock lock(shared_->mutex);
    const std::size_t capacity = shared_->ring.size();
    if (shared_->count == capacity || shared_->stopping) {
      lock.unlock();
      promise.set_value(Status{StatusCode::ResourceExhausted,
                               "evaluateAsync: " + std::to_string(capacity) +
                                   " calls are already queued or running (ClientOptions::async_queue)"});
      return future;
    }
    shared_->ring[(shared_->head + shared_->count) % capacity].emplace(
        Call{function, inputs, outputs, std::move(promise)});
    ++shared_->count;
  }
  shared_->wake.notify_one();
  return future;
}

std::size_t AsyncExecutor::poolFallbacks() const { return shared_->pool->fallbacks(); }

}  // namespace robodiff::client::detail
