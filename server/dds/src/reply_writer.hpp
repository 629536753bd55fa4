#pragma once
// Writing replies on the reply topic, each on its request's channel (the reply writer of the
// caller's partition: reply_channels.hpp): the header every reply carries (server version
// and instance, the request's client and correlation ids, the status), error replies with
// the method's empty body, and EvaluateBatch replies split into chunks. Each reply is
// accounted once with ServiceApi::recordRequest("dds", ...). Safe from any thread.

#include <dds/dds.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>

#include "reply_channels.hpp"
#include "robodiff/schema/dds_codec.hpp"
#include "robodiff/server/fair_scheduler.hpp"
#include "robodiff/server/log.hpp"
#include "robodiff/server/service_api.hpp"

namespace robodiff::server::dds_detail {

// A queued request's place in its writer's quota (fair_scheduler.hpp), given back by
// `release` (FairScheduler::answered) when its first reply is about to be written, before
// the client can send its next request. A refused request's slot was never admitted.
struct QuotaRelease {
  QuotaSlot slot;
  std::function<void(QuotaSlot&)> release;
};

// What a reply needs to know about its request.
struct RequestInfo {
  rpc::RequestHeader header;
  rpc::Method method = rpc::Method::Health;
  Clock::time_point received;
  std::uint32_t knot_count = 0;  // EvaluateBatch: the request's (total_knots of an error reply)
  dds_instance_handle_t publication = 0;  // the writer that sent it (its partition names the caller)
  ReplyChannelPtr channel;                // the reply writer in that partition
  std::shared_ptr<QuotaRelease> quota;    // released before a reply is written
};

class ReplyWriter {
 public:
  ReplyWriter(ServiceApi& service, Logger& log, std::size_t max_sample_bytes)
      : service_(service), log_(log), max_sample_bytes_(max_sample_bytes) {}

  void close() { open_.store(false); }  // stopping: replies are dropped from now on

  // The reply header of `info` with `status`, into a zeroed C header.
  void header(const RequestInfo& info, const Status& status, robodiff_wire_ReplyHeader& out) const;
  // Writes a complete reply sample (header and body filled) and accounts for it.
  void send(const RequestInfo& info, const robodiff_wire_Reply& reply, StatusCode code);
  // A non-OK reply: the status and the method's empty body (one sample, also for a batch).
  void sendError(const RequestInfo& info, const Status& status);
  // An OK reply with a decoded body.
  void sendBody(const RequestInfo& info, const dds_codec::ReplyBody& body);
  // An OK EvaluateBatch reply: `outputs` (knot_count knots of per_knot doubles) in chunks of
  // at most max_sample_bytes, each borrowing its slice of `outputs` (no copy).
  void sendBatch(const RequestInfo& info, std::uint32_t per_knot, std::span<const double> outputs);
  // INVALID_ARGUMENT for a body whose discriminator is no known method, echoing it (not
  // accounted: there is no method to account it under).
  void sendUnknownMethod(const RequestInfo& info, robodiff_wire_Method discriminator);

 private:
  bool write(const RequestInfo& info, const robodiff_wire_Reply& reply);
  void account(const RequestInfo& info, StatusCode code);

  ServiceApi& service_;
  Logger& log_;
  std::size_t max_sample_bytes_;
  std::atomic<bool> open_{true};
};

}  // namespace robodiff::server::dds_detail
