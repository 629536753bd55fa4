#pragma once
// A robot host's ArtifactSource over DDS (docs/fleet.md): asks its build hosts, in order,
// for a function's library built for this robot's x86-64 level; takes it from the first
// that has it, or waits while one builds it; receives it in chunks, checks the signature
// before the first byte and every file after the last, files it in this host's cache.
//
// A build host that stops answering (killed, unplugged) mid-query or mid-transfer is
// given up after call_timeout and the next one is asked; what it had sent is dropped.
// Refusals (an untrusted or bad signature, a changed byte, another function's or another
// CPU's library) are logged, counted per build host, and never reach the cache.

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/entry_transfer.hpp"
#include "robodiff/server/artifact_source.hpp"
#include "robodiff/server/fleet_options.hpp"
#include "robodiff/server/log.hpp"

namespace robodiff::server {

namespace fleet {
class BuildHostLink;
}

// The x86-64 level `target` ("auto": the highest this CPU supports) or
// std::invalid_argument naming what this CPU supports.
std::string resolveFleetTarget(const std::string& target);

class ArtifactFetcher final : public ArtifactSource {
 public:
  // Loads the trusted keys and creates a DDS participant per build host. Throws
  // cache::SigningError (a key file), std::invalid_argument (the target, no build host)
  // or std::runtime_error (DDS) naming the problem.
  ArtifactFetcher(FleetFetchOptions options, Logger& log);
  ~ArtifactFetcher() override;

  ArtifactDelivery fetch(const ArtifactOrder& order, cache::Cache& cache,
                         const std::function<bool()>& cancelled) override;
  rpc::FleetFigures figures() const override;
  const std::string& target() const { return target_; }

 private:
  struct Attempt;
  // From one build host: HAVE -> transferred; BUILDING -> waited for; LACK -> asked to
  // build when `ask_build`. Empty key: not delivered (attempt.problem says why).
  std::string obtain(fleet::BuildHostLink& host, Attempt& attempt, bool ask_build);
  std::string transfer(fleet::BuildHostLink& host, Attempt& attempt, const rpc::QueryArtifactReply& offer);
  static std::string offerProblem(const cache::EntryInfo& info, const Attempt& attempt);
  // The payload into `receiver`, chunk by chunk; false when the host was lost (recorded)
  // or the fetch cancelled. Throws cache::TransferRefused for a chunk that disagrees.
  bool pull(fleet::BuildHostLink& host, Attempt& attempt, cache::EntryReceiver& receiver, const std::string& key);

  FleetFetchOptions options_;
  Logger& log_;
  std::string target_;
  cache::TrustedKeys trusted_;
  std::vector<std::unique_ptr<fleet::BuildHostLink>> hosts_;
  std::atomic<std::uint64_t> fetched_{0}, bytes_{0}, refused_{0}, failures_{0};
};

}  // namespace robodiff::server
