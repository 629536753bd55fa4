#pragma once
// Per-thread scratch for Local evaluation: the compiled function's work buffer and the
// block pointer arrays. One set per thread, shared by every Function the thread calls;
// it only grows, so after a thread's first call on a Function (which sizes it) no call
// allocates. Evaluation does not re-enter itself, so one set per thread is enough.

#include <cstddef>
#include <vector>

namespace robodiff::client::detail {

struct ThreadBuffers {
  std::vector<double> work;
  std::vector<const double*> in;
  std::vector<double*> out;

  // Grows (never shrinks) to hold `work` doubles and the given numbers of block pointers.
  void reserveFor(std::size_t work_doubles, std::size_t in_blocks, std::size_t out_blocks) {
    if (work.size() < work_doubles) work.resize(work_doubles);
    if (in.size() < in_blocks) in.resize(in_blocks);
    if (out.size() < out_blocks) out.resize(out_blocks);
  }
};

inline ThreadBuffers& threadBuffers() {
  thread_local ThreadBuffers buffers;
  return buffers;
}

}  // namespace robodiff::client::detail
