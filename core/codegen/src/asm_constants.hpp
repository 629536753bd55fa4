// The assembly library's constants: read-only pools after every function, one entry per
// distinct bit pattern, each with a local label.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>

namespace robodiff::codegen::detail {

class AsmConstants {
 public:
  // 16 bytes: the double (or mask) in the low lane, `high` in lane 1 (a lane pair's
  // constant; 0 for a scalar's). Bitwise operations and packed ones read all 16.
  std::string label(std::uint64_t bits, std::uint64_t high = 0);
  // The entry's byte offset from the pool's start, .LRDc0 (entries in the order of
  // their first use, 16 bytes apart).
  int offset(std::uint64_t bits, std::uint64_t high = 0);
  std::string vector(std::uint64_t bits);  // 32 bytes: four copies (256-bit operands)
  std::string print() const;

 private:
  std::map<std::pair<std::uint64_t, std::uint64_t>, int> index_;
  std::map<std::uint64_t, int> vector_index_;
};

}  // namespace robodiff::codegen::detail
