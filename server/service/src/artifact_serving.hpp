#pragma once
// A build host's side of a fleet (docs/fleet.md): QueryArtifact and FetchArtifactChunk.
//
// A robot names a function by its portable key and sends the URDF and the spec (with the
// x86-64 level it runs). The build host recomputes the key from them (a robot of another
// robodiff version gets FAILED_PRECONDITION, not a wrong library), looks the library up in
// its cache and answers HAVE with the entry's signed manifest; a library it lacks it
// builds (BUILDING; the robot asks again) when the robot asks for a build. The robot then
// pulls the manifest's files, concatenated in its order, in chunks.
//
// Signed payloads are kept in memory (the latest few) so that chunk requests read no
// file; a payload evicted meanwhile is signed again from the cache.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "function_builds.hpp"
#include "model_entry.hpp"
#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/entry_transfer.hpp"
#include "robodiff/server/service.hpp"
#include "task_queue.hpp"

namespace robodiff::server::detail {

class ArtifactServing {
 public:
  // Loads the signing key. Throws cache::SigningError naming the key file when it cannot.
  ArtifactServing(const ArtifactServingOptions& options, const BuildSettings& build, cache::Cache& cache,
                  workers::WorkerPool& pool, Logger& log);
  ~ArtifactServing();  // stop()
  ArtifactServing(const ArtifactServing&) = delete;
  ArtifactServing& operator=(const ArtifactServing&) = delete;

  Status query(const CallContext& ctx, const rpc::QueryArtifactRequest& request, rpc::QueryArtifactReply& reply);
  Status chunk(const CallContext& ctx, const rpc::FetchArtifactChunkRequest& request,
               rpc::FetchArtifactChunkReply& reply);
  void figures(rpc::FleetFigures& fleet) const;
  // Drops the builds not started and cancels the running ones.
  void stop();

 private:
  struct Build {
    std::string caller;
    bool done = false;
    std::string failure;  // done: empty when it built
  };
  struct Prepared {
    std::shared_ptr<const ModelEntry> model;
    std::string key, spec_json;
  };

  Status prepare(const rpc::QueryArtifactRequest& request, Prepared& prepared);
  std::shared_ptr<const ModelEntry> modelFor(const rpc::QueryArtifactRequest& request, Status& status);
  // The signed payload of `key` (kept, or signed now from the cache); null when absent.
  std::shared_ptr<const cache::SignedEntry> signedEntry(const std::string& key, bool include_sources);
  // BUILDING, LACK or FAILED for a key this host does not have.
  Status absent(const CallContext& ctx, const rpc::QueryArtifactRequest& request, const Prepared& prepared,
                rpc::QueryArtifactReply& reply);
  void build(const Prepared& prepared, const std::string& caller);

  ArtifactServingOptions options_;
  BuildSettings build_settings_;
  cache::Cache& cache_;
  Logger& log_;
  cache::SigningKey signer_;
  workers::WorkerPool& pool_;
  workers::CachedBuilder builder_;

  mutable std::mutex mutex_;
  std::list<std::pair<std::string, std::shared_ptr<const cache::SignedEntry>>> signed_;  // newest first
  std::list<std::pair<std::string, std::shared_ptr<const ModelEntry>>> models_;          // by URDF digest
  std::map<std::string, Build> builds_;  // by key
  std::map<std::string, std::uint32_t> builds_per_caller_;  // queued or running
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> served_{0}, bytes_served_{0}, builds_for_robots_{0};

  TaskQueue build_queue_;  // last: its threads use everything above
};

}  // namespace robodiff::server::detail
