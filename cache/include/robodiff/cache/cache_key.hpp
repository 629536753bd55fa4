// The cache key: the identity of a compiled function library, computed from its content.
//
// A key is the SHA-256 over everything that decides which bytes the build produces:
// the robot (its canonical hash, so the same robot written differently gets the same
// key and one changed mass a new one), the normalised function spec, the generator's
// version and options, the compiler's identity and version, the flags, and the target
// CPU (a -march=native library must never be served to another CPU).
#pragma once

#include <string>
#include <vector>

namespace robodiff::cache {

struct BuildIdentity {
  std::string model_hash;         // canonicalHash(model)
  std::string spec;               // normalizedSpecJson(spec)
  std::string generator;          // codegen::kGeneratorVersion plus builder/codegen options
  std::string compiler;           // the compiler's `--version` line
  std::vector<std::string> flags; // exactly as passed to the compiler
  std::string target_cpu;         // targetCpuIdentity(native, level)

  // The text that is hashed: one "field=value" line per field, in a fixed order.
  std::string canonicalText() const;
  std::string key() const;  // lowercase hex SHA-256 of canonicalText()

  // The same without the compiler's identity: what a host that has no compiler, or
  // another version of it, can compute for the same function, model, flags and target
  // (a robot asking for a library built elsewhere). Two libraries with one portable key
  // compute the same function for the same CPUs; they may differ in their bytes.
  std::string portableText() const;
  std::string portableKey() const;  // lowercase hex SHA-256 of portableText()
};

// What the generated code may assume about the CPU. For a native build: the machine
// architecture, the CPU vendor and model, and its instruction-set flags (from
// /proc/cpuinfo). For a named level ("x86-64-v3"): the architecture and the level.
// Otherwise: only the machine architecture.
std::string targetCpuIdentity(bool native, const std::string& level = "");

// The short name of a build's target that an entry records (EntryInfo::compiler ends with
// " target=<label>"), what a loader checks before it opens the library (runtime/
// target_check.hpp): "generic", the level, or "native:" and 16 hex digits of the SHA-256
// of this CPU's identity.
std::string targetLabel(bool native, const std::string& level = "");

// True when `text` looks like a key (64 lowercase hex digits); keys name directories.
bool isCacheKey(const std::string& text);

}  // namespace robodiff::cache
