#include "batch_runner.hpp"

#include <algorithm>

#include "thread_priority.hpp"

namespace robodiff::server::detail {

BatchRunner::BatchRunner(unsigned threads, unsigned nice) {
  const unsigned helpers = std::max(1u, threads) - 1;
  invited_.reserve(64);
  helpers_.reserve(helpers);
  for (unsigned i = 0; i < helpers; ++i)
    helpers_.emplace_back([this, nice] {
      lowerCallingThreadPriority(nice);
      loop();
    });
}

BatchRunner::~BatchRunner() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : helpers_) t.join();
}

// Takes pieces until none is left.
void BatchRunner::work(Batch& batch) {
  for (;;) {
    const std::uint64_t i = batch.next.fetch_add(1, std::memory_order_relaxed);
    if (i >= batch.pieces) return;
    batch.call(batch.piece, i);
    if (batch.done.fetch_add(1, std::memory_order_acq_rel) + 1 == batch.pieces) batch.done.notify_all();
  }
}

void BatchRunner::runPieces(std::uint64_t pieces, unsigned helpers, void (*call)(void*, std::uint64_t), void* piece) {
  if (pieces == 0) return;
  Batch batch;  // on this stack: run() does not return while a helper may touch it
  batch.pieces = pieces;
  batch.call = call;
  batch.piece = piece;
  const std::size_t invited = std::min<std::uint64_t>({helpers, helpers_.size(), pieces - 1});
  if (invited > 0) {
    {
      std::lock_guard lock(mutex_);
      invited_.insert(invited_.end(), invited, &batch);
    }
    if (invited == 1)
      wake_.notify_one();
    else
      wake_.notify_all();
  }
  work(batch);
  for (std::uint64_t d = batch.done.load(std::memory_order_acquire); d != pieces;
       d = batch.done.load(std::memory_order_acquire))
    batch.done.wait(d, std::memory_order_acquire);
  if (invited > 0) {
    // Invitations not taken up are withdrawn; helpers inside work() are waited for.
    std::unique_lock lock(mutex_);
    std::erase(invited_, &batch);
    left_.wait(lock, [&] { return batch.active == 0; });
  }
}

void BatchRunner::loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_ || !invited_.empty(); });
    if (stopping_) return;
    Batch* batch = invited_.front();
    invited_.erase(invited_.begin());
    ++batch->active;
    lock.unlock();
    work(*batch);
    lock.lock();
    // Under the lock: the caller cannot see active == 0 (and leave) before this is done.
    if (--batch->active == 0) left_.notify_all();
  }
}

}  // namespace robodiff::server::detail
