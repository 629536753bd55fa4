// `robodiff warmup --server`: the running server builds the functions (LoadModel and
// GetFunction for every pair, then ListFunctions until each is compiled or its build
// failed), shown with warmup's progress display.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "robodiff/workers/cached_builder.hpp"

namespace robodiff::cli {

struct ServerWarmupOptions {
  std::string server;                     // --server's value; empty: $ROBODIFF_SERVER, else auto
  std::optional<double> timeout_seconds;  // how long to wait for everything to compile (default 900)
  bool json = false;
};

// Throws CLI::RuntimeError(1) when a function failed (each is listed with its reason),
// ServiceError when the server cannot be reached or refuses a call outright.
void warmupOnServer(const std::vector<workers::BuildTarget>& targets, const ServerWarmupOptions& options);

}  // namespace robodiff::cli
