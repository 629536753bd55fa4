// The Service's fleet methods (docs/fleet.md): a build host serves QueryArtifact and
// FetchArtifactChunk (artifact_serving.hpp); every server answers FleetStatus with its role.
#include "robodiff/server/service.hpp"
#include "service_state.hpp"

namespace robodiff::server {

Status Service::queryArtifact(const CallContext& ctx, const rpc::QueryArtifactRequest& request,
                              rpc::QueryArtifactReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  return detail::guarded(s.log, "QueryArtifact", [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, "QueryArtifact");
    if (!s.artifacts) return ServiceApi::notABuildHost();
    if (request.spec_json.size() > s.options.max_spec_bytes)
      return {StatusCode::ResourceExhausted, "spec_json: " + std::to_string(request.spec_json.size()) +
                                                 " bytes, past the limit of " +
                                                 std::to_string(s.options.max_spec_bytes) + " bytes (max_spec_bytes)"};
    return s.artifacts->query(ctx, request, reply);
  });
}

Status Service::fetchArtifactChunk(const CallContext& ctx, const rpc::FetchArtifactChunkRequest& request,
                                   rpc::FetchArtifactChunkReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  return detail::guarded(s.log, "FetchArtifactChunk", [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, "FetchArtifactChunk");
    if (!s.artifacts) return ServiceApi::notABuildHost();
    return s.artifacts->chunk(ctx, request, reply);
  });
}

Status Service::fleetStatus(const CallContext& ctx, const rpc::FleetStatusRequest&, rpc::FleetStatusReply& reply) {
  State& s = *state_;
  const InFlight in_flight(s.in_flight);
  return detail::guarded(s.log, "FleetStatus", [&]() -> Status {
    if (ctx.expired()) return detail::deadlineExceeded(ctx, "FleetStatus");
    reply.fleet = fleet();
    return {};
  });
}

rpc::FleetFigures Service::fleet() const {
  const State& s = *state_;
  rpc::FleetFigures f;
  if (s.options.artifact_source) f = s.options.artifact_source->figures();
  f.role = s.artifacts ? "build" : s.options.artifact_source ? "robot" : "standalone";
  if (s.artifacts) s.artifacts->figures(f);
  return f;
}

}  // namespace robodiff::server
