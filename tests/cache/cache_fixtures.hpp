#pragma once
// What the cache tests share: keys from names and an entry's description.
#include <string>

#include "robodiff/cache/cache.hpp"
#include "robodiff/model/canonical.hpp"

namespace robodiff::cache {

inline std::string keyOf(const std::string& name) { return sha256Hex(name); }

// A plausible arm7 entry for `function`; a non-zero build time, so that what repair
// restores from entry.json is told apart from a default.
inline EntryInfo infoFor(const std::string& function) {
  EntryInfo info;
  info.model_hash = sha256Hex("model");
  info.robot = "arm7";
  info.function = function;
  info.spec = R"({"function":")" + function + R"("})";
  info.sizes = R"({"inputs":[7,7,7],"outputs":[7]})";
  info.compiler = "cc (test) 1.0 -O0";
  info.build_seconds = 1.5;
  return info;
}

}  // namespace robodiff::cache
