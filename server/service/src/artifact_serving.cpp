#include "artifact_serving.hpp"

#include <thread>

#include "model_loading.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "robodiff/model/canonical.hpp"

namespace robodiff::server::detail {
namespace {

constexpr std::size_t kModelsKept = 8;
constexpr std::size_t kBuildsRemembered = 1024;

std::int64_t unixNow() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string signedName(const std::string& key, bool include_sources) {
  return key + (include_sources ? "+src" : "");
}

}  // namespace

ArtifactServing::ArtifactServing(const ArtifactServingOptions& options, const BuildSettings& build,
                                 cache::Cache& cache, workers::WorkerPool& pool, Logger& log)
    : options_(options),
      build_settings_(build),
      cache_(cache),
      log_(log),
      signer_(cache::SigningKey::load(options.signing_key)),
      pool_(pool),
      builder_(cache, pool, builderOptions(build)),
      build_queue_("robot-builds", std::max(1u, build.compile_threads), 0, [this](const std::string& what) {
        log_.error("internal_error", {{"message", what}});
      }) {
  log_.info("fleet_build_host", {{"signing_key", options_.signing_key.string()},
                                 {"key_id", signer_.keyId()},
                                 {"build_for_robots", options_.build_for_robots && build.compile}});
}

ArtifactServing::~ArtifactServing() { stop(); }

void ArtifactServing::stop() {
  // Builds not started are dropped (build() sees stopping_); running ones are cancelled
  // (their workers killed; the builder abandons their claims).
  if (stopping_.exchange(true)) return;
  while (build_queue_.running() != 0) {
    for (const workers::WorkerInfo& w : pool_.workers())
      if (w.job) pool_.cancel(*w.job);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  build_queue_.stop(false);
}

std::shared_ptr<const ModelEntry> ArtifactServing::modelFor(const rpc::QueryArtifactRequest& request,
                                                           Status& status) {
  const std::string digest = sha256Hex(request.urdf) + (request.floating_base ? "+ff" : "");
  {
    std::lock_guard lock(mutex_);
    for (const auto& [d, model] : models_)
      if (d == digest) return model;
  }
  rpc::LoadModelRequest load;
  load.urdf = request.urdf;
  load.floating_base = request.floating_base;
  std::shared_ptr<ModelEntry> entry;
  status = loadModelEntry(load, build_settings_.urdf_limits.max_bytes, build_settings_.urdf_limits, entry);
  if (!status.ok()) return nullptr;
  entry->source_name = "the robot's URDF";
  std::lock_guard lock(mutex_);
  models_.emplace_front(digest, entry);
  if (models_.size() > kModelsKept) models_.pop_back();
  return entry;
}

Status ArtifactServing::prepare(const rpc::QueryArtifactRequest& request, Prepared& prepared) {
  FunctionSpec spec;
  try {
    spec = parseFunctionSpec(request.spec_json, "spec_json");
  } catch (const std::exception& e) {
    return {StatusCode::InvalidArgument, language::boundedText(e.what(), kMaxErrorBytes)};
  }
  if (spec.build.target.empty() && spec.build.march_native)
    return {StatusCode::FailedPrecondition,
            "the spec asks for -march=native: a robot asks for the x86-64 level it runs (build.target x86-64-v2, "
            "-v3, -v4) or generic x86-64; a build host never compiles for its own CPU on a robot's behalf"};
  Status status;
  prepared.model = modelFor(request, status);
  if (!prepared.model) return status;
  const cache::PreparedBuild p =
      cache::prepareBuild(*prepared.model->model, prepared.model->id, spec, "", build_settings_.compiler);
  if (p.info.portable_key != request.portable_key)
    return {StatusCode::FailedPrecondition,
            "the robot asked for portable key " + language::boundedText(request.portable_key) +
                " but this build host computes " + p.info.portable_key +
                " for that URDF and spec: the two run different robodiff versions (generator " +
                std::string(p.identity.generator.substr(0, p.identity.generator.find(';'))) + " here)"};
  prepared.key = p.key;
  prepared.spec_json = p.identity.spec;
  return {};
}

std::shared_ptr<const cache::SignedEntry> ArtifactServing::signedEntry(const std::string& key,
                                                                      bool include_sources) {
  const std::string name = signedName(key, include_sources);
  {
    std::lock_guard lock(mutex_);
    for (auto it = signed_.begin(); it != signed_.end(); ++it)
      if (it->first == name) {
        signed_.splice(signed_.begin(), signed_, it);  // most recently used first
        return it->second;
      }
  }
  const std::optional<cache::Artifact> artifact = cache_.find(key);  // verified against the index
  if (!artifact) return nullptr;
  auto entry = std::make_shared<const cache::SignedEntry>(
      cache::signEntry(*artifact, signer_, include_sources, unixNow()));
  std::lock_guard lock(mutex_);
  signed_.emplace_front(name, entry);
  while (signed_.size() > std::max<std::size_t>(1, options_.signed_entries_kept)) signed_.pop_back();
  return entry;
}

Status ArtifactServing::query(const CallContext& ctx, const rpc::QueryArtifactRequest& request,
                              rpc::QueryArtifactReply& reply) {
  Prepared prepared;
  if (Status s = prepare(request, prepared); !s.ok()) return s;
  reply.key = prepared.key;
  if (const auto entry = signedEntry(prepared.key, request.include_sources)) {
    reply.state = rpc::ArtifactState::Have;
    reply.manifest_json = entry->manifest;
    reply.signature_hex = entry->signature_hex;
    reply.payload_bytes = entry->payloadBytes();
    return {};
  }
  return absent(ctx, request, prepared, reply);
}

Status ArtifactServing::absent(const CallContext& ctx, const rpc::QueryArtifactRequest& request,
                               const Prepared& prepared, rpc::QueryArtifactReply& reply) {
  std::lock_guard lock(mutex_);
  if (const auto it = builds_.find(prepared.key); it != builds_.end()) {
    if (!it->second.done) {
      reply.state = rpc::ArtifactState::Building;
      reply.builds_queued = static_cast<std::uint32_t>(builds_per_caller_[it->second.caller]);
      return {};
    }
    if (!it->second.failure.empty()) {
      reply.state = rpc::ArtifactState::Failed;
      reply.message = it->second.failure;
      return {};
    }
  }
  const bool may_build = options_.build_for_robots && build_settings_.compile;
  if (!request.build || !may_build) {
    reply.state = rpc::ArtifactState::Lack;
    reply.message = may_build ? "not in this build host's cache" : "not in this build host's cache, and it builds "
                                                                   "nothing for robots (fleet.build_for_robots, "
                                                                   "build.compile)";
    return {};
  }
  const std::string caller(ctx.caller.name.empty() ? std::string(ctx.client_id) : ctx.caller.name);
  std::uint32_t& queued = builds_per_caller_[caller];
  if (queued >= options_.max_builds_per_caller)
    return {StatusCode::ResourceExhausted, "caller " + caller + " has " + std::to_string(queued) +
                                               " builds queued or running on this build host already "
                                               "(fleet.max_builds_per_robot); ask again when one is done"};
  ++queued;
  builds_[prepared.key] = Build{caller, false, {}};
  if (!build_queue_.post([this, prepared, caller] { build(prepared, caller); })) {
    --queued;
    builds_.erase(prepared.key);
    return {StatusCode::Unavailable, "this build host is stopping"};
  }
  builds_for_robots_.fetch_add(1, std::memory_order_relaxed);
  reply.state = rpc::ArtifactState::Building;
  reply.builds_queued = queued;
  log_.info("fleet_build_requested", {{"key", prepared.key}, {"caller", caller}, {"robot", prepared.model->model->name}});
  return {};
}

void ArtifactServing::build(const Prepared& prepared, const std::string& caller) {
  if (stopping_) return;
  workers::BuildTarget target;
  target.urdf_path = "the robot's URDF (" + prepared.model->model->name + ")";
  target.floating_base = prepared.model->floating_base;
  target.spec_path = "the spec " + caller + " asked for";
  target.urdf_text = prepared.model->urdf;
  target.model = prepared.model->model;
  target.model_hash = prepared.model->id;
  target.spec_text = prepared.spec_json;
  workers::BuildStatus status;
  try {
    status = builder_.buildAll({target}).at(0);
  } catch (const std::exception& e) {
    status.state = workers::BuildState::Failed;
    status.message = e.what();
  }
  const bool built = status.state == workers::BuildState::Done || status.state == workers::BuildState::Cached;
  std::string failure;
  if (!built) failure = language::boundedText(status.message.empty() ? "the build failed" : status.message, 1024);
  else if (status.key != prepared.key) failure = "the build made key " + status.key + ", not " + prepared.key;
  std::lock_guard lock(mutex_);
  // A built library is found in the cache from now on; a failure is remembered (bounded)
  // so that robots asking again learn why instead of building it again.
  if (failure.empty()) builds_.erase(prepared.key);
  else builds_[prepared.key] = Build{caller, true, failure};
  if (builds_.size() > kBuildsRemembered) std::erase_if(builds_, [](const auto& b) { return b.second.done; });
  if (std::uint32_t& queued = builds_per_caller_[caller]; queued > 0) --queued;
  if (failure.empty())
    log_.info("fleet_build_done", {{"key", prepared.key}, {"caller", caller}, {"seconds", status.seconds}});
  else
    log_.warn("fleet_build_failed", {{"key", prepared.key}, {"caller", caller}, {"message", failure}});
}

Status ArtifactServing::chunk(const CallContext& ctx, const rpc::FetchArtifactChunkRequest& request,
                              rpc::FetchArtifactChunkReply& reply) {
  if (!cache::isCacheKey(request.key))
    return {StatusCode::InvalidArgument, "key " + language::quote(language::boundedText(request.key)) +
                                             " is not a cache key (64 lowercase hex digits)"};
  if (options_.chunk_delay.count() > 0) std::this_thread::sleep_for(options_.chunk_delay);
  const auto entry = signedEntry(request.key, request.include_sources);
  if (!entry)
    return {StatusCode::NotFound, "library " + request.key + " is not in this build host's cache (any more)"};
  const std::uint32_t max = request.max_bytes == 0 ? options_.chunk_bytes
                                                   : std::min(request.max_bytes, options_.chunk_bytes);
  reply.offset = request.offset;
  reply.payload_bytes = entry->payloadBytes();
  entry->readPayload(request.offset, max, reply.data);
  bytes_served_.fetch_add(reply.data.size(), std::memory_order_relaxed);
  if (!reply.data.empty() && request.offset + reply.data.size() == reply.payload_bytes) {
    served_.fetch_add(1, std::memory_order_relaxed);
    log_.info("fleet_artifact_served", {{"key", request.key},
                                        {"bytes", reply.payload_bytes},
                                        {"caller", ctx.caller.name.empty() ? std::string(ctx.client_id)
                                                                           : ctx.caller.name}});
  }
  return {};
}

void ArtifactServing::figures(rpc::FleetFigures& fleet) const {
  fleet.artifacts_served = served_.load(std::memory_order_relaxed);
  fleet.bytes_served = bytes_served_.load(std::memory_order_relaxed);
  fleet.builds_for_robots = builds_for_robots_.load(std::memory_order_relaxed);
}

}  // namespace robodiff::server::detail
