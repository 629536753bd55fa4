// Closest names by optimal-string-alignment distance, case-insensitive, with bounded work.
#include "robodiff/language/suggest.hpp"

#include <algorithm>
#include <set>
#include <utility>

#include "robodiff/language/bounded_text.hpp"

namespace robodiff::language {
namespace {

// Longer names are compared on their first kCompared characters: a 10 MB name costs no
// more than a 256-character one.
constexpr std::size_t kCompared = 256;
// Containment counts from this many characters on ('hand' in 'panda_hand'), so that a
// one- or two-letter name is not "contained" in half of the candidates.
constexpr std::size_t kMinContained = 3;

std::string folded(const std::string& text) {
  std::string out = text.substr(0, std::min(text.size(), kCompared));
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

// Edit distance with insertions, deletions, substitutions and swaps of adjacent
// characters (each substring edited at most once). Three rolling rows: O(|a| |b|) time.
std::size_t osaDistance(const std::string& a, const std::string& b) {
  const std::size_t n = b.size();
  std::vector<std::size_t> before(n + 1), previous(n + 1), current(n + 1);
  for (std::size_t j = 0; j <= n; ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= n; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      std::size_t best = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) best = std::min(best, before[j - 2] + 1);
      current[j] = best;
    }
    std::swap(before, previous);
    std::swap(previous, current);
  }
  return previous[n];
}

std::size_t lengthGap(std::size_t a, std::size_t b) { return a > b ? a - b : b - a; }

}  // namespace

std::vector<std::string> closestNames(const std::string& name, const std::vector<std::string>& candidates,
                                      std::size_t max_count) {
  const std::string key = folded(name);
  const std::size_t threshold = std::max<std::size_t>(2, key.size() / 3);
  std::vector<std::pair<std::size_t, std::string>> found;  // (distance, candidate)
  std::set<std::string> seen;
  for (const std::string& candidate : candidates) {
    if (candidate == name || candidate.empty() || !seen.insert(candidate).second) continue;
    const std::string other = folded(candidate);
    const bool contains = std::min(key.size(), other.size()) >= kMinContained &&
                          (other.find(key) != std::string::npos || key.find(other) != std::string::npos);
    // The distance is at least the difference in length: skip hopeless candidates early.
    if (!contains && lengthGap(key.size(), other.size()) > threshold) continue;
    const std::size_t distance = osaDistance(key, other);
    if (contains || distance <= threshold) found.emplace_back(distance, candidate);
  }
  std::sort(found.begin(), found.end());
  std::vector<std::string> names;
  for (std::size_t i = 0; i < found.size() && i < max_count; ++i) names.push_back(std::move(found[i].second));
  return names;
}

std::string didYouMean(const std::string& name, const std::vector<std::string>& candidates) {
  const std::vector<std::string> names = closestNames(name, candidates);
  if (names.empty()) return "";
  std::string text = " (did you mean ";
  for (std::size_t i = 0; i < names.size(); ++i) text += (i == 0 ? "" : ", ") + quote(names[i]);
  return text + "?)";
}

}  // namespace robodiff::language
