// Compact addressing for large functions' single-knot code: array elements (work
// buffer, inputs, outputs) read and written through a few base pointers, each within a
// one-byte displacement of the elements it reaches, and constants read from a table
// through such pointers. Large functions run at the speed their code streams into the
// instruction cache; this makes the instructions shorter (docs/code-generation.md,
// "Compact addressing").
//
// The body goes into a function of its own that takes the arrays and the base pointers
// as restrict parameters: the compiler cannot fold a base back into its array's address
// there, and knows that no two of them alias. Each element is reached through one
// pointer only, so that restrict holds: windows do not overlap, and no access of more
// than one element (a pair, four zeros, a memset) crosses a window's edge.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace robodiff::codegen::detail {

// Used for functions of CodegenOptions::compact_addressing_from instructions and more,
// in two passes over one function body: first every access and constant the printer
// asks for is counted (and printed as usual), then plan() chooses the windows and the
// table, and the second pass prints through them.
class CompactAddressing {
 public:
  // `array`: the C name of an array of doubles ("w", "i0", "o2").
  std::string element(const std::string& array, std::uint32_t index);  // "w[35]" or "b1[-3]"
  // The address of `width` consecutive elements: "w + 35" or "b1 - 3".
  std::string address(const std::string& array, std::uint32_t index, std::uint32_t width);
  std::string constant(const std::string& literal);  // "0.316" or "k0[5]"
  // The array's first `size` elements are accessed through the array's own pointer.
  void whole(const std::string& array, std::uint32_t size);

  // Chooses the windows (the most used first) and the constants' table from the counts.
  void plan();

  // Before the function: the constants' table, named `table`, or nothing.
  std::string table(const std::string& table) const;
  // The base pointers as the body's parameters ("double* restrict b0", ...) and as the
  // caller's arguments ("w + 299", "out[2] + 40", "rd_f_k + 16", ...).
  std::vector<std::string> parameters() const;
  std::vector<std::string> arguments(const std::string& table) const;

 private:
  struct Window {
    std::string array;
    std::uint32_t center = 0;  // the base points at array + center
  };
  int windowOf(const std::string& array, std::uint32_t index) const;
  bool fits(const std::string& array, std::uint32_t lo, std::uint32_t hi) const;
  std::string through(const std::string& array, std::uint32_t index, bool address);
  std::size_t constantBases() const;

  bool planned_ = false;
  std::map<std::pair<std::string, std::uint32_t>, std::uint32_t> uses_;  // elements past a byte's reach
  std::map<std::string, std::vector<std::pair<std::uint32_t, std::uint32_t>>> spans_;  // [first, last] wider than one
  std::map<std::string, std::uint32_t> constant_uses_;
  std::vector<Window> windows_;
  std::vector<std::string> constants_;  // the table, most used first
  std::map<std::string, std::uint32_t> constant_index_;
};

}  // namespace robodiff::codegen::detail
