#pragma once
// Per-thread scratch for Local evaluation: the compiled function's work buffer, the
// block pointer arrays, and for batches the knots regrouped block after block. One set per thread, shared by every Function the thread calls;
// it only grows, so after a thread's first call on a Function (which sizes it) no call
// allocates. Evaluation does not re-enter itself, so one set per thread is enough.

#include <cstddef>
#include <vector>

namespace robodiff::client::detail {

struct ThreadBuffers {
  std::vector<double> work;
  std::vector<const double*> in;
  std::vector<double*> out;
  std::vector<double> batch_in, batch_out;  // a chunk's knots, block after block

  // Grows (never shrinks) to hold `work` doubles and the given numbers of block pointers.
  void reserveFor(std::size_t work_doubles, std::size_t in_blocks, std::size_t out_blocks) {
    if (work.size() < work_doubles) work.resize(work_doubles);
    if (in.size() < in_blocks) in.resize(in_blocks);
    if (out.size() < out_blocks) out.resize(out_blocks);
  }
  // Grows (never shrinks) the regrouping buffers to the given numbers of doubles.
  void reserveBatch(std::size_t in_doubles, std::size_t out_doubles) {
    if (batch_in.size() < in_doubles) batch_in.resize(in_doubles);
    if (batch_out.size() < out_doubles) batch_out.resize(out_doubles);
  }
};

inline ThreadBuffers& threadBuffers() {
  thread_local ThreadBuffers buffers;
  return buffers;
}

}  // namespace robodiff::client::detail
