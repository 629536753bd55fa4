#include "asm_constants.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <vector>

namespace robodiff::codegen::detail {
namespace {

std::string quad(std::uint64_t bits) {
  char text[32];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(bits));
  return text;
}

// A pool's section and its entries in the order of their labels.
template <class Key, class Print>
std::string printPool(const std::map<Key, int>& index, const std::string& section, int align, const char* prefix,
                      Print entry) {
  if (index.empty()) return {};
  std::ostringstream s;
  s << "\t.section\t" << section << "\n\t.p2align " << align << "\n";
  std::vector<std::pair<int, Key>> ordered;
  for (const auto& [key, i] : index) ordered.emplace_back(i, key);
  std::sort(ordered.begin(), ordered.end());
  for (const auto& [i, key] : ordered) s << prefix << i << ":\n\t.quad\t" << entry(key) << "\n";
  return s.str();
}

}  // namespace

std::string AsmConstants::label(std::uint64_t bits, std::uint64_t high) {
  auto it = index_.emplace(std::make_pair(bits, high), static_cast<int>(index_.size())).first;
  return ".LRDc" + std::to_string(it->second);
}

int AsmConstants::offset(std::uint64_t bits, std::uint64_t high) {
  label(bits, high);
  return 16 * index_.at({bits, high});
}

std::string AsmConstants::vector(std::uint64_t bits) {
  auto it = vector_index_.emplace(bits, static_cast<int>(vector_index_.size())).first;
  return ".LRDv" + std::to_string(it->second);
}

std::string AsmConstants::print() const {
  // Not a mergeable section: the linker keeps its entries where they are, 16 bytes apart,
  // as the functions' reads relative to the pool's base need.
  const std::string pairs = printPool(index_, ".rodata", 4, ".LRDc", [](const std::pair<std::uint64_t, std::uint64_t>& k) {
    return quad(k.first) + ", " + (k.second == 0 ? std::string("0") : quad(k.second));
  });
  const std::string vectors = printPool(vector_index_, ".rodata.cst32,\"aM\",@progbits,32", 5, ".LRDv", [](std::uint64_t bits) {
    const std::string q = quad(bits);
    return q + ", " + q + ", " + q + ", " + q;
  });
  return pairs + vectors;
}

}  // namespace robodiff::codegen::detail
