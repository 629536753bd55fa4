#pragma once
// One build host as a robot host sees it: a DDS connection to its service, the two artifact
// calls, and what this robot has got from it (FleetPeer's figures). Thread-safe.

#include <memory>
#include <mutex>
#include <string>

#include "robodiff/client/dds_connection.hpp"
#include "robodiff/schema/messages.hpp"
#include "robodiff/server/fleet_options.hpp"

namespace robodiff::server::fleet {

class BuildHostLink {
 public:
  // Creates the DDS participant (no build host needed yet). Throws std::runtime_error
  // naming the service when DDS refuses.
  BuildHostLink(const std::string& service, const FleetFetchOptions& options);

  const std::string& service() const { return service_; }
  Status query(const rpc::QueryArtifactRequest& request, rpc::QueryArtifactReply& reply);
  Status chunk(const rpc::FetchArtifactChunkRequest& request, rpc::FetchArtifactChunkReply& reply);

  // Counts for FleetStatus.
  void delivered(std::uint64_t bytes, double seconds);
  void refused(const std::string& problem);
  void failed(const std::string& problem);
  rpc::FleetPeer figures() const;

 private:
  Status answered(Status status);  // records reachability (and the instance id once)

  std::string service_;
  std::chrono::milliseconds call_timeout_;
  std::unique_ptr<client::DdsConnection> connection_;
  mutable std::mutex mutex_;
  rpc::FleetPeer peer_;
};

}  // namespace robodiff::server::fleet
