#include "build_host_link.hpp"

namespace robodiff::server::fleet {
namespace {

client::DdsConnectionOptions connectionOptions(const std::string& service, const FleetFetchOptions& o) {
  client::DdsConnectionOptions c;
  c.domain_id = o.domain_id;
  c.service_name = service;
  c.match_timeout = o.match_timeout;
  c.security = o.security;
  c.connection.default_timeout = o.call_timeout;
  c.lease = std::chrono::seconds(2);  // a build host forgets a robot that died soon
  return c;
}

// Statuses that say the build host itself is gone or stuck, not that it refused.
bool lost(StatusCode code) {
  return code == StatusCode::Unavailable || code == StatusCode::DeadlineExceeded;
}

}  // namespace

BuildHostLink::BuildHostLink(const std::string& service, const FleetFetchOptions& options)
    : service_(service),
      call_timeout_(options.call_timeout),
      connection_(std::make_unique<client::DdsConnection>(connectionOptions(service, options))) {
  peer_.service = service;
}

Status BuildHostLink::answered(Status status) {
  bool need_id = false;
  {
    std::lock_guard lock(mutex_);
    peer_.reachable = !lost(status.code);
    need_id = peer_.reachable && peer_.instance_id.empty();
  }
  if (need_id) {  // once: which server answers under this service name
    rpc::HealthRequest request;
    rpc::HealthReply reply;
    if (connection_->call(client::HealthCall{&request, &reply}, {call_timeout_}).ok()) {
      std::lock_guard lock(mutex_);
      peer_.instance_id = reply.server_instance_id;
    }
  }
  return status;
}

Status BuildHostLink::query(const rpc::QueryArtifactRequest& request, rpc::QueryArtifactReply& reply) {
  return answered(connection_->call(client::QueryArtifactCall{&request, &reply}, {call_timeout_}));
}

Status BuildHostLink::chunk(const rpc::FetchArtifactChunkRequest& request, rpc::FetchArtifactChunkReply& reply) {
  return answered(connection_->call(client::FetchArtifactChunkCall{&request, &reply}, {call_timeout_}));
}

void BuildHostLink::delivered(std::uint64_t bytes, double seconds) {
  std::lock_guard lock(mutex_);
  ++peer_.artifacts_fetched;
  peer_.bytes_fetched += bytes;
  peer_.fetch_seconds += seconds;
}

void BuildHostLink::refused(const std::string& problem) {
  std::lock_guard lock(mutex_);
  ++peer_.refusals;
  peer_.last_problem = problem;
}

void BuildHostLink::failed(const std::string& problem) {
  std::lock_guard lock(mutex_);
  ++peer_.failures;
  peer_.last_problem = problem;
}

rpc::FleetPeer BuildHostLink::figures() const {
  std::lock_guard lock(mutex_);
  return peer_;
}

}  // namespace robodiff::server::fleet
