#include "compact_addressing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace robodiff::codegen::detail {
namespace {

// x86-64 encodes a displacement of -128..127 bytes in one byte, else in four: doubles
// -16..15 from a base. An array's first 16 elements are within reach of its own pointer.
constexpr std::uint32_t kReachBelow = 16, kReachAbove = 15;
constexpr std::uint32_t kWindow = kReachBelow + kReachAbove + 1;
constexpr std::uint32_t kArrayBases = 8;     // base pointers for arrays, at most
constexpr std::uint32_t kConstantBases = 2;  // and for the constants' table (a window each)
constexpr std::uint32_t kMinimumUses = 4;    // a base pays for its register from this many

// gcc turns products with these into adds or exact multiplies only when it sees them.
bool keptLiteral(const std::string& literal) {
  const double v = std::fabs(std::strtod(literal.c_str(), nullptr));
  if (v == 0.0 || !std::isfinite(v)) return true;
  int e = 0;
  return std::frexp(v, &e) == 0.5;  // a power of two
}

std::string offset(std::int64_t d, bool address) {
  if (!address) return "[" + std::to_string(d) + "]";
  return d < 0 ? " - " + std::to_string(-d) : " + " + std::to_string(d);
}

// "i2" -> "in[2]", "o0" -> "out[0]", "w" -> "w": an array as the caller names it.
std::string callerName(const std::string& array) {
  if (array == "w") return array;
  return (array[0] == 'i' ? "in[" : "out[") + array.substr(1) + "]";
}

}  // namespace

std::string CompactAddressing::element(const std::string& array, std::uint32_t index) {
  return through(array, index, false);
}

std::string CompactAddressing::address(const std::string& array, std::uint32_t index, std::uint32_t width) {
  if (!planned_ && width > 1) spans_[array].push_back({index, index + width - 1});
  return through(array, index, true);
}

void CompactAddressing::whole(const std::string& array, std::uint32_t size) {
  if (!planned_ && size > 0) spans_[array].push_back({0, size - 1});
}

std::string CompactAddressing::through(const std::string& array, std::uint32_t index, bool address) {
  if (!planned_) {
    if (index > kReachAbove) ++uses_[{array, index}];
  } else if (int b = windowOf(array, index); b >= 0) {
    return "b" + std::to_string(b) + offset(std::int64_t{index} - windows_[b].center, address);
  }
  return array + offset(index, address);
}

std::string CompactAddressing::constant(const std::string& literal) {
  if (!planned_) {
    if (!keptLiteral(literal)) ++constant_uses_[literal];
    return literal;
  }
  auto it = constant_index_.find(literal);
  if (it == constant_index_.end()) return literal;
  const std::uint32_t k = it->second;
  return "k" + std::to_string(k / kWindow) + offset(std::int64_t{k % kWindow} - std::int64_t{kReachBelow}, false);
}

int CompactAddressing::windowOf(const std::string& array, std::uint32_t index) const {
  for (std::size_t b = 0; b < windows_.size(); ++b) {
    const Window& w = windows_[b];
    if (w.array == array && index + kReachBelow >= w.center && index <= w.center + kReachAbove)
      return static_cast<int>(b);
  }
  return -1;
}

// Whether a window over elements [lo, hi] of `array` keeps every element behind one
// pointer: it overlaps no window chosen before, and no wider access crosses its edges.
bool CompactAddressing::fits(const std::string& array, std::uint32_t lo, std::uint32_t hi) const {
  for (const Window& w : windows_)
    if (w.array == array && lo <= w.center + kReachAbove && w.center <= hi + kReachBelow) return false;
  auto it = spans_.find(array);
  if (it == spans_.end()) return true;
  for (const auto& [first, last] : it->second) {
    const bool inside_first = first >= lo && first <= hi, inside_last = last >= lo && last <= hi;
    if (inside_first != inside_last || (first < lo && last > hi)) return false;
  }
  return true;
}

void CompactAddressing::plan() {
  // Greedy: the window covering the most remaining uses (from one of them, or centred
  // on it), until the bases run out or no window pays.
  auto remaining = uses_;
  while (windows_.size() < kArrayBases && !remaining.empty()) {
    Window best;
    std::uint32_t best_uses = 0;
    for (const auto& [key, n] : remaining) {
      for (std::uint32_t center : {key.second + kReachBelow, key.second}) {
        if (center < kReachBelow) continue;
        std::uint32_t covered = 0;
        for (auto it = remaining.lower_bound({key.first, center - kReachBelow});
             it != remaining.end() && it->first.first == key.first && it->first.second <= center + kReachAbove; ++it)
          covered += it->second;
        if (covered > best_uses && fits(key.first, center - kReachBelow, center + kReachAbove)) {
          best_uses = covered;
          best = {key.first, center};
        }
      }
    }
    if (best_uses < kMinimumUses) break;
    windows_.push_back(best);
    for (auto it = remaining.begin(); it != remaining.end();)
      it = windowOf(it->first.first, it->first.second) >= 0 ? remaining.erase(it) : std::next(it);
  }
  std::vector<std::pair<std::uint32_t, std::string>> ranked;
  for (const auto& [literal, n] : constant_uses_) ranked.push_back({n, literal});
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [n, literal] : ranked) {
    if (constants_.size() == kConstantBases * kWindow) break;
    constant_index_[literal] = static_cast<std::uint32_t>(constants_.size());
    constants_.push_back(literal);
  }
  planned_ = true;
}

std::size_t CompactAddressing::constantBases() const { return (constants_.size() + kWindow - 1) / kWindow; }

std::string CompactAddressing::table(const std::string& table) const {
  if (constants_.empty()) return {};
  // Padded to the last base's window, so that every base points into the array.
  const std::size_t size = std::max<std::size_t>(constants_.size(), (constantBases() - 1) * kWindow + kReachBelow);
  std::ostringstream s;
  s << "static const double " << table << "[" << size << "] = {";
  for (std::size_t k = 0; k < size; ++k) s << (k ? ", " : "") << (k < constants_.size() ? constants_[k] : "0.0");
  s << "};\n";
  return s.str();
}

std::vector<std::string> CompactAddressing::parameters() const {
  std::vector<std::string> p;
  for (std::size_t b = 0; b < windows_.size(); ++b)
    p.push_back(std::string(windows_[b].array[0] == 'i' ? "const " : "") + "double* restrict b" + std::to_string(b));
  for (std::size_t b = 0; b < constantBases(); ++b) p.push_back("const double* restrict k" + std::to_string(b));
  return p;
}

std::vector<std::string> CompactAddressing::arguments(const std::string& table) const {
  std::vector<std::string> a;
  for (const Window& w : windows_) a.push_back(callerName(w.array) + " + " + std::to_string(w.center));
  for (std::size_t b = 0; b < constantBases(); ++b) a.push_back(table + " + " + std::to_string(b * kWindow + kReachBelow));
  return a;
}

}  // namespace robodiff::codegen::detail
