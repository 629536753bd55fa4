#pragma once
// The threads behind Function::evaluateAsync: a fixed set of threads fed by a bounded
// ring of calls, and futures whose shared state comes from a fixed pool of blocks, so
// that an asynchronous call allocates nothing once the executor has started (the pool
// and the ring are sized up front; a call beyond the ring's capacity completes at once
// with RESOURCE_EXHAUSTED instead of queueing without bound).
//
// Lifetime: the Client::Impl owns the executor, and a queued call keeps its Function (and
// so the Client::Impl) alive. The threads and the pool therefore live in shared state
// that outlives the executor object: the last reference to a Client can be dropped by one
// of these threads, which then must not join itself.

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "robodiff/client/client.hpp"

namespace robodiff::client::detail {

// Fixed-size blocks for the futures' shared states; falls back to operator new when
// empty or when a request is larger than a block (neither happens in steady state).
class BlockPool {
 public:
  static constexpr std::size_t kBlockSize = 256;
  explicit BlockPool(std::size_t blocks);
  void* allocate(std::size_t bytes);
  void deallocate(void* p, std::size_t bytes) noexcept;
  std::size_t fallbacks() const;  // allocations that went to operator new

 private:
  bool owns(const void* p) const;
  std::unique_ptr<std::byte[]> arena_;
  std::size_t blocks_;
  std::vector<void*> free_;  // reserved to `blocks`: pushing never allocates
  mutable std::mutex mutex_;
  std::size_t fallbacks_ = 0;
};

// An allocator over a shared BlockPool (copies share it; the pool lives while any
// allocated state does).
template <class T>
struct PoolAllocator {
  using value_type = T;
  std::shared_ptr<BlockPool> pool;
  explicit PoolAllocator(std::shared_ptr<BlockPool> p) : pool(std::move(p)) {}
  template <class U>
  PoolAllocator(const PoolAllocator<U>& other) : pool(other.pool) {}
  T* allocate(std::size_t n) { return static_cast<T*>(pool->allocate(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { pool->deallocate(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const PoolAllocator<U>& other) const { return pool == other.pool; }
};

class AsyncExecutor {
 public:
  // `threads` evaluation threads, at most `capacity` calls queued or running.
  AsyncExecutor(std::size_t threads, std::size_t capacity);
  ~AsyncExecutor();
  AsyncExecutor(const AsyncExecutor&) = delete;
  AsyncExecutor& operator=(const AsyncExecutor&) = delete;

  // Queues function.evaluate(inputs, outputs); the future carries its status.
  std::future<Status> submit(const Function& function, std::span<const double> inputs, std::span<double> outputs);
  std::size_t poolFallbacks() const;

  struct Shared;

 private:
  std::shared_ptr<Shared> shared_;
  std::vector<std::thread> threads_;
};

}  // namespace robodiff::client::detail
