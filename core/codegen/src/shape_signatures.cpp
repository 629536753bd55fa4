#include "shape_signatures.hpp"

#include <algorithm>
#include <utility>

#include "operand_ref.hpp"

namespace robodiff::codegen::detail {
namespace {

using symbolic::NodeId;

// Levels kept (a signature at level d covers the operations up to d reads below a node),
// roughly geometric: the ranking needs "how deep", not the exact level.
constexpr int kKeptLevels[] = {1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128};

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

std::uint64_t combine(std::uint64_t seed, std::uint64_t value) { return mix(seed ^ (value + 0x9e3779b97f4a7c15ull)); }

constexpr std::uint64_t kConstantLeaf = 0x51ull, kInputLeaf = 0x73ull;

}  // namespace

ShapeSignatures::ShapeSignatures(const symbolic::Graph& g, const std::vector<char>& of_interest) {
  const std::size_t n = g.size();
  std::vector<std::uint64_t> previous(n), current(n);
  for (NodeId id = 0; id < n; ++id)
    previous[id] = of_interest[id] ? mix(static_cast<std::uint64_t>(g.node(id).op) + 1) : kInputLeaf;
  auto operand = [&](NodeId id, int k) -> std::uint64_t {
    const Ref r = resolve(g, g.node(id).args[k]);
    if (r.is_constant) return kConstantLeaf;
    return combine(previous[r.base], r.negated ? 1 : 0);
  };
  int level = 0;
  for (const int keep : kKeptLevels) {
    for (; level < keep; ++level) {
      current = previous;
      for (NodeId id = 0; id < n; ++id) {
        if (!of_interest[id]) continue;
        const symbolic::Op op = g.node(id).op;
        const int arity = symbolic::arity(op);
        std::uint64_t a = arity > 0 ? operand(id, 0) : 0, b = arity > 1 ? operand(id, 1) : 0;
        if (arity == 2 && symbolic::isCommutative(op) && b < a) std::swap(a, b);
        std::uint64_t s = combine(combine(static_cast<std::uint64_t>(op) + 1, a), b);
        if (arity > 2) s = combine(s, operand(id, 2));
        current[id] = s;
      }
      std::swap(previous, current);
    }
    levels_.push_back(keep);
    kept_.push_back(previous);
  }
}

int ShapeSignatures::matchDepth(NodeId a, NodeId b) const {
  // Same shape at a level means the same shape at every level below it (hash collisions
  // aside): the first level that differs, by bisection.
  std::size_t lo = 0, hi = levels_.size();  // levels_[< lo] match, levels_[>= hi] differ
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (kept_[mid][a] == kept_[mid][b]) lo = mid + 1;
    else hi = mid;
  }
  return lo == 0 ? 0 : levels_[lo - 1];
}

}  // namespace robodiff::codegen::detail
