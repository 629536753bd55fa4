#include "robodiff/server/artifact_fetcher.hpp"

#include <chrono>
#include <set>
#include <stdexcept>
#include <thread>

#include "build_host_link.hpp"
#include "robodiff/cache/entry_transfer.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/cache/target_check.hpp"
#include "robodiff/functions/function_spec.hpp"

namespace robodiff::server {

using Clock = std::chrono::steady_clock;

std::string resolveFleetTarget(const std::string& target) {
  std::string supported;
  for (const char* level : kTargetLevels)
    if (cache::cpuSupportsLevel(level)) supported = supported.empty() ? level : supported + ", " + level;
  if (target == "auto") {
    for (auto it = std::rbegin(kTargetLevels); it != std::rend(kTargetLevels); ++it)
      if (cache::cpuSupportsLevel(*it)) return *it;
    throw std::invalid_argument("fleet.target = \"auto\": this CPU supports no x86-64 level beyond the baseline");
  }
  for (const char* level : kTargetLevels)
    if (target == level) {
      if (cache::cpuSupportsLevel(level)) return target;
      throw std::invalid_argument("fleet.target = \"" + target + "\": this CPU does not support it (it supports " +
                                  (supported.empty() ? std::string("none") : supported) + ")");
    }
  throw std::invalid_argument("fleet.target = \"" + target +
                              "\": expected \"auto\", \"x86-64-v2\", \"x86-64-v3\" or \"x86-64-v4\"");
}

// One fetch: the request every build host is asked, and what went wrong so far.
struct ArtifactFetcher::Attempt {
  rpc::QueryArtifactRequest request;
  std::string target;
  cache::Cache* cache = nullptr;
  const std::function<bool()>* cancelled = nullptr;
  std::string function_id;
  std::vector<std::string> problems;  // "service: what", one per build host tried
  std::set<const fleet::BuildHostLink*> done;  // failed or refused already: not asked again

  bool stop() const { return (*cancelled)(); }
};

ArtifactFetcher::ArtifactFetcher(FleetFetchOptions options, Logger& log)
    : options_(std::move(options)), log_(log), target_(resolveFleetTarget(options_.target)) {
  if (options_.build_hosts.empty())
    throw std::invalid_argument("fleet.role = \"robot\" needs fleet.build_hosts: the build hosts' DDS service names");
  if (options_.trusted_keys.empty())
    throw std::invalid_argument("fleet.role = \"robot\" needs fleet.trusted_keys: the build hosts' public keys "
                                "(robodiff keygen writes NAME.pub)");
  trusted_ = cache::TrustedKeys::load(options_.trusted_keys);
  for (const std::string& service : options_.build_hosts)
    hosts_.push_back(std::make_unique<fleet::BuildHostLink>(service, options_));
  std::string keys;
  for (const std::string& id : trusted_.keyIds()) keys += (keys.empty() ? "" : ",") + id;
  log_.info("fleet_robot", {{"target", target_}, {"build_hosts", hosts_.size()}, {"trusted_keys", keys}});
}

ArtifactFetcher::~ArtifactFetcher() = default;

ArtifactDelivery ArtifactFetcher::fetch(const ArtifactOrder& order, cache::Cache& cache,
                                        const std::function<bool()>& cancelled) {
  // The robot's own level for a spec that asks for this CPU (native, the default): a build
  // host never builds `native`. A named level or generic x86-64 is asked for as it is.
  FunctionSpec spec = *order.spec;
  if (spec.build.target.empty() && spec.build.march_native) {
    spec.build.target = target_;
    spec.build.march_native = false;  // a level, not this CPU (function_spec.hpp's BuildOptions)
  }
  Attempt attempt;
  attempt.request.portable_key = cache::preparePortableKey(order.model_hash, spec, "");
  attempt.request.urdf = order.urdf;
  attempt.request.floating_base = order.floating_base;
  attempt.request.spec_json = normalizedSpecJson(spec);
  attempt.request.include_sources = options_.include_sources;
  attempt.target = spec.build.target;
  attempt.cache = &cache;
  attempt.cancelled = &cancelled;
  attempt.function_id = order.function_id;

  // First who has it (asking nobody to build), then who builds it, in the configured order.
  for (const bool ask_build : {false, true})
    for (const auto& host : hosts_) {
      if (attempt.stop()) return {{}, "cancelled"};
      if (attempt.done.count(host.get()) != 0) continue;
      if (std::string key = obtain(*host, attempt, ask_build); !key.empty()) return {key, {}};
    }
  failures_.fetch_add(1, std::memory_order_relaxed);
  std::string why;
  for (const std::string& p : attempt.problems) why += (why.empty() ? "" : "; ") + p;
  return {{}, why.empty() ? "no build host answered" : why};
}

std::string ArtifactFetcher::obtain(fleet::BuildHostLink& host, Attempt& attempt, bool ask_build) {
  const Clock::time_point give_up = Clock::now() + options_.build_wait;
  attempt.request.build = ask_build;
  for (;;) {
    rpc::QueryArtifactReply reply;
    const Status status = host.query(attempt.request, reply);
    if (!status.ok()) {
      attempt.problems.push_back(host.service() + ": " + status.message);
      host.failed(status.message);
      attempt.done.insert(&host);
      return {};
    }
    switch (reply.state) {
      case rpc::ArtifactState::Have:
        attempt.done.insert(&host);  // whatever comes of it, once per fetch
        return transfer(host, attempt, reply);
      case rpc::ArtifactState::Lack:
        if (!ask_build) return {};  // asked again in the second round, to build it
        attempt.problems.push_back(host.service() + ": " + reply.message);
        return {};
      case rpc::ArtifactState::Failed:
        attempt.done.insert(&host);
        attempt.problems.push_back(host.service() + ": its build failed: " + reply.message);
        host.failed("build failed: " + reply.message);
        return {};
      case rpc::ArtifactState::Building: break;
    }
    if (Clock::now() >= give_up) {
      attempt.problems.push_back(host.service() + ": still building after fleet.build_wait");
      return {};
    }
    if (attempt.stop()) return {};
    std::this_thread::sleep_for(options_.build_poll);
    attempt.request.build = false;  // asked once; now only whether it is done
  }
}

// What is wrong with a signed manifest for this fetch, or empty: another function (a swapped
// library), another target than asked, or one this CPU cannot run.
std::string ArtifactFetcher::offerProblem(const cache::EntryInfo& info, const Attempt& attempt) {
  if (info.portable_key != attempt.request.portable_key)
    return "the signed manifest is for portable key " + info.portable_key + ", not the one asked (" +
           attempt.request.portable_key + ")";
  const std::string label = " target=" + (attempt.target.empty() ? std::string("generic") : attempt.target);
  if (info.compiler.size() < label.size() ||
      info.compiler.compare(info.compiler.size() - label.size(), label.size(), label) != 0)
    return "the library was built for another target than " + attempt.target + " (" + info.compiler + ")";
  return cache::targetProblem(info.compiler);
}

bool ArtifactFetcher::pull(fleet::BuildHostLink& host, Attempt& attempt, cache::EntryReceiver& receiver,
                           const std::string& key) {
  rpc::FetchArtifactChunkRequest request;
  request.key = key;
  request.include_sources = attempt.request.include_sources;
  request.max_bytes = options_.chunk_bytes;
  while (!receiver.complete()) {
    if (attempt.stop()) return false;
    request.offset = receiver.received();
    rpc::FetchArtifactChunkReply chunk;
    const Status status = host.chunk(request, chunk);
    if (!status.ok()) {
      const std::string problem = "lost after " + std::to_string(request.offset) + " of " +
                                  std::to_string(receiver.payloadBytes()) + " bytes: " + status.message;
      host.failed(problem);
      attempt.problems.push_back(host.service() + ": " + problem);
      log_.warn("fleet_transfer_lost",
                {{"function_id", attempt.function_id}, {"build_host", host.service()}, {"message", problem}});
      return false;
    }
    if (chunk.offset != request.offset || chunk.payload_bytes != receiver.payloadBytes() || chunk.data.empty())
      throw cache::TransferRefused("chunk at offset " + std::to_string(request.offset) +
                                   " disagrees with the manifest (offset " + std::to_string(chunk.offset) +
                                   ", payload " + std::to_string(chunk.payload_bytes) + " bytes, " +
                                   std::to_string(chunk.data.size()) + " data bytes)");
    receiver.append(chunk.data.data(), chunk.data.size());
  }
  return true;
}

std::string ArtifactFetcher::transfer(fleet::BuildHostLink& host, Attempt& attempt,
                                      const rpc::QueryArtifactReply& offer) {
  const Clock::time_point started = Clock::now();
  auto fail = [&](const std::string& problem, bool refusal) {
    (refusal ? host.refused(problem) : host.failed(problem));
    attempt.problems.push_back(host.service() + ": " + (refusal ? "refused: " : "") + problem);
    if (!refusal) return std::string();
    refused_.fetch_add(1, std::memory_order_relaxed);
    log_.warn("fleet_artifact_refused", {{"function_id", attempt.function_id}, {"build_host", host.service()},
                                         {"key", offer.key}, {"problem", problem}});
    return std::string();
  };
  try {
    cache::TransferLimits limits;
    limits.max_payload_bytes = options_.max_artifact_bytes;
    cache::EntryReceiver receiver(offer.manifest_json, offer.signature_hex, trusted_, offer.key, limits);
    if (const std::string problem = offerProblem(receiver.manifest().info, attempt); !problem.empty())
      return fail(problem, true);
    if (!pull(host, attempt, receiver, offer.key)) return {};  // lost (recorded) or cancelled
    const cache::ImportResult result = receiver.install(*attempt.cache);
    if (result.status == cache::ImportResult::Status::Refused) return fail(result.problem, false);
    const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
    fetched_.fetch_add(1, std::memory_order_relaxed);
    bytes_.fetch_add(receiver.payloadBytes(), std::memory_order_relaxed);
    host.delivered(receiver.payloadBytes(), seconds);
    log_.info("fleet_artifact_fetched",
              {{"function_id", attempt.function_id}, {"build_host", host.service()}, {"key", offer.key},
               {"bytes", receiver.payloadBytes()}, {"seconds", seconds}, {"signer", result.signer}});
    return offer.key;
  } catch (const cache::TransferRefused& e) {
    return fail(e.what(), true);
  } catch (const std::exception& e) {  // this host's disk (the scratch directory, the cache)
    return fail(e.what(), false);
  }
}

rpc::FleetFigures ArtifactFetcher::figures() const {
  rpc::FleetFigures f;
  f.target = target_;
  f.artifacts_fetched = fetched_.load(std::memory_order_relaxed);
  f.bytes_fetched = bytes_.load(std::memory_order_relaxed);
  f.artifacts_refused = refused_.load(std::memory_order_relaxed);
  f.fetch_failures = failures_.load(std::memory_order_relaxed);
  for (const auto& host : hosts_) f.peers.push_back(host->figures());
  return f;
}

}  // namespace robodiff::server
