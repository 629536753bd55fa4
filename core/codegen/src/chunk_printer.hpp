// Prints one chunk of a lowered function (lowering.hpp) as the body of a C function:
// single-knot code (`double` locals, lane pairs as `rd_pair`) or batched code (`rd_v`
// locals, RD_W knots in the lanes), addressed plainly or compactly
// (compact_addressing.hpp). Internal to the C emitter.
#pragma once

#include <cstdint>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "compact_addressing.hpp"
#include "entry_kernels.hpp"
#include "lowering.hpp"
#include "output_groups.hpp"
#include "robodiff/codegen/function_definition.hpp"

namespace robodiff::codegen::detail {

// Concatenation by appending (GCC 12 warns falsely, -Wrestrict, on "literal" + string&&).
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::string s;
  (s += ... += parts);
  return s;
}

// Scalar: one knot, `double` locals. Vector: RD_W knots in the lanes of `rd_v` locals.
enum class Flavour { Scalar, Vector };

// Prints one chunk of a lowered function as the body of a C function.
class ChunkPrinter {
 public:
  // Output blocks of at least this many values are claimed by the batched chunk.
  static constexpr std::uint32_t kClaimMinimum = 256;

  ChunkPrinter(const FunctionDefinition& f, Flavour flavour) : f_(f), flavour_(flavour) {}

  // true: sin and cos by the _in_range kernels, with no range check of their own (the
  // function checks its arguments at entry).
  void inRangeKernels(bool on) { in_range_ = on; }

  // Every sin-cos kernel of the chunk computed at the body's entry (entry_kernels.hpp),
  // its site taking the results: `kernels` of the chunk printed, `angles` the inputs they
  // take. Both must outlive print().
  void kernelsAtEntry(const std::vector<EntryKernel>& kernels,
                      const std::vector<std::pair<std::uint32_t, std::uint32_t>>& angles) {
    entry_kernels_ = &kernels;
    entry_angles_ = &angles;
  }

  // true: the chunk holds all of its function's output stores, which are packed into
  // 32-byte groups where the function is bound by its stores (output_groups.hpp).
  void packOutputGroups(bool on) { pack_groups_ = on; }

  // `signature` is the function's declaration up to, not including, the body.
  // `first`: the function's first chunk, where the batched flavour claims its outputs.
  // `compact`: not empty, the body is addressed compactly (compact_addressing.hpp): its
  // constants in the table `compact`_k, the body itself in the function `compact`_body.
  std::string print(const std::string& signature, const Chunk& chunk, bool first = false,
                    const std::string& compact = "");

 private:
  std::string printOnce(const std::string& signature, const Chunk& chunk, bool first, const std::string& compact);

  // A compactly addressed body: a function `compact`_body taking the arrays and the base
  // pointers as restrict parameters, called by `signature`.
  void printCompactBody(const std::string& signature, const Chunk& chunk, const std::string& compact,
                        const std::set<std::uint32_t>& in_blocks, const std::set<std::uint32_t>& out_blocks,
                        bool uses_work);

  bool vector() const { return flavour_ == Flavour::Vector; }
  const char* kernelSuffix() const { return in_range_ ? "_in_range" : ""; }
  static std::string localName(std::uint32_t slot) {
    return cat("t", std::to_string(slot));
  }
  const char* type() const { return vector() ? "rd_v" : "double"; }

  // An array's element, its address, a constant: through the compact addressing, if any.
  std::string element(const std::string& array, std::uint32_t index) const {
    return compact_ ? compact_->element(array, index) : cat(array, "[", std::to_string(index), "]");
  }
  std::string address(const std::string& array, std::uint32_t index, std::uint32_t width) const {
    return compact_ ? compact_->address(array, index, width) : cat(array, " + ", std::to_string(index));
  }
  std::string literal(double value) const;

  // "rd_pair p3 = " the first time a pair local is assigned, "p3 = " after.
  std::string assignPair(std::uint32_t slot);

  // "double t3 = " the first time a local is assigned in this function, "t3 = " after.
  std::string assign(std::uint32_t slot);

  // An operand as a C expression. `helper_argument`: it is passed to a lane-wise helper,
  // so a constant must become a vector.
  std::string operand(const Operand& o, bool helper_argument = false) const;

  // An operand of + or - as its magnitude and whether it is negated, so that the sign
  // folds into the operator (a - b, not a + -b).
  std::pair<std::string, bool> signedOperand(const Operand& o) const;

  std::string expression(const Instr& ins) const;

  // Structural zeros of a single knot's block up to this many are stored four at a time
  // (below); more are cleared with one memset of the block.
  // A memset costs ~35 ns before anything else runs (gcc inlines `rep stos`), so it only
  // pays for large blocks: Solo-12's frame Jacobian (63 zeros) 77 -> 38 ns, Talos's (170)
  // 37 -> 25 ns, Talos's M(q) (744 zeros) 530 ns with the memset, 570 ns without.
  static constexpr std::uint32_t kStoredZerosMaximum = 256;

  void printZeros(std::uint32_t block, const std::vector<ZeroRun>& runs);

  void printInstr(const Instr& ins, const Chunk& chunk);
  // The entry block of a body with kernels at entry, the body's zero stores within it
  // (entry_kernels.hpp), and which kernel each instruction is.
  void printEntryBlock(const Chunk& chunk);
  // In a body with kernels at entry, a kernel's site: its results copied to its
  // locals (true); false elsewhere.
  bool atEntry(const Instr& ins, const Chunk& chunk);
  // A StoreOutput of a packed group: its value named, and the group stored after its last.
  void printGroupedStore(const Instr& ins, std::uint32_t at);

  const FunctionDefinition& f_;
  Flavour flavour_;
  bool in_range_ = false;
  const std::vector<EntryKernel>* entry_kernels_ = nullptr;
  const std::vector<std::pair<std::uint32_t, std::uint32_t>>* entry_angles_ = nullptr;
  std::vector<std::int64_t> entry_unit_;  // per instruction: its kernel's first unit, or -1
  bool pack_groups_ = false;
  OutputGroupPlan groups_;  // of the chunk being printed
  std::ostringstream out_;
  std::vector<char> declared_, declared_pair_;
  CompactAddressing* compact_ = nullptr;  // during print() of a compactly addressed body
};

}  // namespace robodiff::codegen::detail
