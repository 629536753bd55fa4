// A build job: a robot and a function spec -> a compiled library published in the cache.
//
// The requesting process prepares it (cache::prepareBuild: the cache key and the index
// row, computed from the canonical model and the normalised spec), claims the key in the
// cache, and sends the job to a worker; the worker runs executeBuild: load the URDF,
// trace, differentiate, emit, compile (the compiler is the worker's child), publish to
// the cache under the claim. The request travels as JSON (toJson / buildRequestFromJson).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"
#include "robodiff/model/urdf_limits.hpp"

namespace robodiff::workers {

struct BuildRequest {
  std::string urdf;             // the URDF text
  std::string urdf_source;      // where it came from, for messages (a path)
  UrdfLimits urdf_limits;       // the requester's: a URDF it accepted is never refused here
  bool floating_base = false;
  std::string spec;             // the spec's JSON text
  std::string spec_source;      // where it came from, for messages
  std::string function_name;    // C name; empty: the spec's function
  std::string compiler;         // the compiler program; empty: $CC or cc
  std::uint64_t compiler_memory_limit_bytes = std::uint64_t{4} << 30;
  std::chrono::milliseconds compiler_timeout = std::chrono::minutes(10);
  unsigned compiler_jobs = 1;   // translation units compiled at once inside this build
  std::string cache_dir;
  // The budget the requester opened the cache with: publish() trims the cache to it.
  std::uint64_t cache_budget_bytes = cache::CacheOptions{}.budget_bytes;
  cache::Claim claim;
  cache::EntryInfo info;
};

std::string toJson(const BuildRequest& request);
// Throws std::invalid_argument naming the missing or mistyped field.
BuildRequest buildRequestFromJson(const std::string& json_text);

// The outcome of a build, as the worker reports it.
struct BuildOutcome {
  bool ok = false;
  std::string error_kind;  // "invalid_urdf", "invalid_spec", "graph_too_large", "compile_failed",
                           // "compile_timeout", "compile_memory", "compiler_missing", "cache", "internal"
  std::string message;
  std::string compiler_output;  // on a compile failure
  std::string key;
  double seconds = 0;           // the whole build, in the worker
  std::uint64_t operations = 0, library_bytes = 0;
};

std::string toJson(const BuildOutcome& outcome);
BuildOutcome buildOutcomeFromJson(const std::string& json_text);

// Runs a build in this process (the worker's job). `progress` is told each stage
// ("model", "trace", "compile", "publish"). Never throws: failures are in the outcome.
BuildOutcome executeBuild(const BuildRequest& request,
                          const std::function<void(const std::string& stage)>& progress = {});

}  // namespace robodiff::workers
