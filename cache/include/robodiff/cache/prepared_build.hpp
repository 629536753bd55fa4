// The recipe of a build's cache key, in one place: what a build of (robot, spec) is
// before anything is built — its identity (so its key), the index row it will get, and
// the library options the builder uses. Every process that looks a library up or builds
// one (robodiffd, warmup, compute, the client library, batch jobs, the worker checking
// its claim) prepares it here, so all of them agree on the key.
#pragma once

#include <string>
#include <vector>

#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::cache {

struct PreparedBuild {
  BuildIdentity identity;
  std::string key;
  EntryInfo info;          // info.sizes: known once built
  LibraryOptions options;  // as the builder will use them
};

// The identity and index row of (model, spec) built with `compiler` (program; empty: $CC
// or cc). `model_hash` is canonicalHash(model), computed once where the model was loaded
// and passed along. `function_name`: the C name; empty: the spec's function. Runs the
// compiler once per process to learn its identity (then remembered). Throws
// codegen::CompileError(CannotRun) when the compiler cannot be run.
PreparedBuild prepareBuild(const Model& model, const std::string& model_hash, const FunctionSpec& spec,
                           const std::string& function_name, const std::string& compiler);

// The portable key (BuildIdentity::portableKey) of what prepareBuild would prepare, without
// running a compiler: what a host that has none looks an imported or fetched library up by.
std::string preparePortableKey(const std::string& model_hash, const FunctionSpec& spec,
                               const std::string& function_name);

// The portable keys under which a library computing `spec` may be found for this CPU: the
// spec's own (preparePortableKey), then, when the spec names no target and asks for
// march_native (the default), the same spec built for each x86-64 level this CPU supports
// (kTargetLevels, cpuSupportsLevel), highest first: what a robot host fetched from a build
// host, which compiles for a level, never for `native`.
std::vector<std::string> portableKeysFor(const std::string& model_hash, const FunctionSpec& spec,
                                         const std::string& function_name);

}  // namespace robodiff::cache
