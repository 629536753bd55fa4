#pragma once
// Who holds a shared model or function, and how many times: LoadModel and GetFunction take
// a reference for their caller, Release gives back one of the caller's own. Functions and
// models are shared by content (the same spec from two callers is one entry), so each
// caller's references are counted apart and one caller's Release never drops another's.
// Guarded by the registry's mutex.

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace robodiff::server::detail {

class Holders {
 public:
  // One more reference for `caller`; returns the total.
  std::uint32_t add(const std::string& caller) {
    ++counts_[caller];
    return ++total_;
  }
  // One of `caller`'s references fewer; false when it holds none.
  bool drop(std::string_view caller) {
    const auto it = counts_.find(caller);
    if (it == counts_.end()) return false;
    if (--it->second == 0) counts_.erase(it);
    --total_;
    return true;
  }
  // Every reference of every caller (an operator's forced release).
  void clear() {
    counts_.clear();
    total_ = 0;
  }
  bool holds(std::string_view caller) const { return counts_.find(caller) != counts_.end(); }
  std::uint32_t total() const { return total_; }
  std::vector<std::string> callers() const {
    std::vector<std::string> out;
    for (const auto& [caller, count] : counts_) out.push_back(caller);
    return out;
  }

 private:
  std::map<std::string, std::uint32_t, std::less<>> counts_;
  std::uint32_t total_ = 0;
};

}  // namespace robodiff::server::detail
