#pragma once
// Runs the pieces of one EvaluateBatch on several threads: the calling thread and the
// batch threads take pieces from a shared counter until none is left, so a batch never
// waits for a busy helper (the caller does the work itself). run() returns when every
// piece has finished and no helper touches the batch any more. Nothing is allocated per
// batch once the invitation list has grown to its working size.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace robodiff::server::detail {

class BatchRunner {
 public:
  // `threads` is the parallelism including the caller: threads - 1 helpers are started,
  // each `nice` nicer than the thread that made the runner (thread_priority.hpp).
  explicit BatchRunner(unsigned threads, unsigned nice = 0);
  ~BatchRunner();
  BatchRunner(const BatchRunner&) = delete;
  BatchRunner& operator=(const BatchRunner&) = delete;

  unsigned threads() const { return static_cast<unsigned>(helpers_.size()) + 1; }

  // Calls piece(i) once for each i in [0, pieces), on the caller and up to `helpers`
  // helper threads; returns when all are done. piece must not throw.
  template <class Piece>
  void run(std::uint64_t pieces, unsigned helpers, Piece& piece) {
    runPieces(
        pieces, helpers, [](void* p, std::uint64_t i) { (*static_cast<Piece*>(p))(i); }, &piece);
  }

 private:
  struct Batch {
    std::uint64_t pieces = 0;
    void (*call)(void*, std::uint64_t) = nullptr;
    void* piece = nullptr;
    std::atomic<std::uint64_t> next{0};
    std::atomic<std::uint64_t> done{0};
    unsigned active = 0;  // helpers inside work(); guarded by mutex_
  };
  void runPieces(std::uint64_t pieces, unsigned helpers, void (*call)(void*, std::uint64_t), void* piece);
  static void work(Batch& batch);
  void loop();

  std::mutex mutex_;
  std::condition_variable wake_;  // helpers: an invitation or stopping
  std::condition_variable left_;  // callers: a helper left a batch
  std::vector<Batch*> invited_;   // one entry per helper invited, oldest first
  bool stopping_ = false;
  std::vector<std::thread> helpers_;
};

}  // namespace robodiff::server::detail
