// Reply headers, error replies and chunked EvaluateBatch replies on the DDS reply topic.
#include "reply_writer.hpp"

#include "robodiff/schema/dds_batch_chunks.hpp"

namespace robodiff::server::dds_detail {

void ReplyWriter::header(const RequestInfo& info, const Status& status, robodiff_wire_ReplyHeader& out) const {
  rpc::ReplyHeader h;
  h.schema_version = {kSchemaVersionMajor, kSchemaVersionMinor};
  h.server_instance_id = service_.instanceId();
  h.client_id = info.header.client_id;
  h.correlation_id = info.header.correlation_id;
  h.status = status;
  dds_codec::toWire(h, out);
}

bool ReplyWriter::write(const RequestInfo& info, const robodiff_wire_Reply& reply) {
  if (info.quota) info.quota->release(info.quota->slot);
  if (!open_.load() || !info.channel) return false;  // stopped: the client sees the server gone instead
  const dds_return_t rc = dds_write(info.channel->writer, &reply);
  if (rc == DDS_RETCODE_OK) return true;
  // After stop() the writer is deleted under running tasks: expected, not worth a warning.
  if (open_.load())
    log_.warn("dds_reply_write_failed", {{"method", rpc::toString(info.method)},
                                         {"client_id", info.header.client_id},
                                         {"correlation_id", info.header.correlation_id},
                                         {"partition", info.channel->partition},
                                         {"error", dds_strretcode(rc)}});
  return false;
}

void ReplyWriter::account(const RequestInfo& info, StatusCode code) {
  service_.recordRequest("dds", info.method, code,
                         std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - info.received));
}

void ReplyWriter::send(const RequestInfo& info, const robodiff_wire_Reply& reply, StatusCode code) {
  write(info, reply);
  account(info, code);
}

void ReplyWriter::sendError(const RequestInfo& info, const Status& status) {
  dds_codec::WireReply reply;
  header(info, status, reply->header);
  dds_codec::ReplyBody body = dds_codec::emptyReplyBody(info.method);
  if (auto* batch = std::get_if<rpc::EvaluateBatchReply>(&body)) {
    batch->chunk_index = 0;
    batch->chunk_count = 1;  // a non-OK status ends the reply: one sample
    batch->total_knots = info.knot_count;
  }
  dds_codec::toWire(body, reply->body);
  send(info, reply.get(), status.code);
}

void ReplyWriter::sendBody(const RequestInfo& info, const dds_codec::ReplyBody& body) {
  dds_codec::WireReply reply;
  header(info, Status{}, reply->header);
  dds_codec::toWire(body, reply->body);
  send(info, reply.get(), StatusCode::Ok);
}

void ReplyWriter::sendBatch(const RequestInfo& info, std::uint32_t per_knot, std::span<const double> outputs) {
  const std::uint32_t total = info.knot_count;
  const dds_codec::ChunkPlan plan = dds_codec::planBatchChunks(total, per_knot, max_sample_bytes_);
  dds_codec::WireReply reply;  // one sample reused: the header stays, the body is rewritten
  header(info, Status{}, reply->header);
  reply->body._d = robodiff_wire_METHOD_EVALUATE_BATCH;
  auto& chunk = reply->body._u.evaluate_batch;
  for (std::uint32_t i = 0; i < plan.chunk_count; ++i) {
    chunk.chunk_index = i;
    chunk.chunk_count = plan.chunk_count;
    chunk.total_knots = total;
    chunk.first_knot = plan.firstKnot(i);
    chunk.knot_count = plan.knotCount(i, total);
    dds_codec::borrowDoubles(chunk.outputs, outputs.subspan(std::size_t{chunk.first_knot} * per_knot,
                                                            std::size_t{chunk.knot_count} * per_knot));
    const bool written = write(info, reply.get());
    dds_codec::detachDoubles(chunk.outputs);  // borrowed: never freed by the sample
    if (!written) break;
  }
  account(info, StatusCode::Ok);
}

void ReplyWriter::sendUnknownMethod(const RequestInfo& info, robodiff_wire_Method discriminator) {
  dds_codec::WireReply reply;
  header(info,
         {StatusCode::InvalidArgument, "unknown method " + std::to_string(static_cast<std::uint32_t>(discriminator)) +
                                           " (this server knows 0.." + std::to_string(rpc::kMethodCount - 1) +
                                           "); is the client newer than the server?"},
         reply->header);
  reply->body._d = discriminator;  // no union member: nothing else to send or free
  write(info, reply.get());
}

}  // namespace robodiff::server::dds_detail
