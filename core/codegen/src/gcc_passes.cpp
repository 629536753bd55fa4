#include "gcc_passes.hpp"

#include "compiler_family.hpp"

namespace robodiff::codegen::detail {
namespace {

// Passes whose work the generator has done already, or that have none to do in its
// straight-line code: measured off one by one and together (gcc 12, the anchors'
// libraries), each neutral or faster at run time and together 11-20% less compile.
const char* const kToggles[] = {
    // Common subexpressions are shared in the graph, so global CSE and PRE find none.
    "-fno-gcse", "-fno-tree-pre", "-fno-code-hoisting", "-fno-rerun-cse-after-loop", "-fno-cse-follow-jumps",
    // Constants are folded in the graph; nothing is an integer range.
    "-fno-tree-ccp", "-fno-tree-bit-ccp", "-fno-tree-vrp",
    // Lanes are paired by the generator (lane pairs, 32-byte output groups); gcc's own
    // straight-line vectoriser made several single-knot functions slower.
    "-fno-tree-slp-vectorize",
    // Each output is stored once, as a double or a vector.
    "-fno-dse", "-fno-store-merging",
    // A function or two per file, with one branch at most: nothing to fold or thread.
    "-fno-ipa-icf", "-fno-ipa-modref", "-fno-thread-jumps", "-fno-tree-dominator-opts", "-fno-tree-tail-merge",
    "-fno-crossjumping"};

}  // namespace

std::vector<std::string> gccPassToggles(const std::string& version_text) {
  // -fno-ipa-modref, the newest of the flags, came with gcc 11.
  if (!isGnuGcc(version_text) || majorVersion(version_text) < 11) return {};
  return {std::begin(kToggles), std::end(kToggles)};
}

}  // namespace robodiff::codegen::detail
