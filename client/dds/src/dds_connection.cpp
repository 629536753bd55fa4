// DdsConnection: sending requests, matching, and the receive thread that routes replies.
#include "robodiff/client/dds_connection.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "pending_calls.hpp"
#include "robodiff/schema/dds_batch_chunks.hpp"
#include "robodiff/schema/dds_codec.hpp"

namespace robodiff::client {

using dds_detail::PendingCall;
using dds_detail::PendingCalls;
using Clock = std::chrono::steady_clock;

namespace {

// "2 s", "0.3 s", "150 ms".
std::string seconds(Clock::duration d) {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(d).count();
  char text[64];
  if (ms < 1000) std::snprintf(text, sizeof text, "%lld ms", static_cast<long long>(ms));
  else if (ms % 1000 == 0) std::snprintf(text, sizeof text, "%lld s", static_cast<long long>(ms / 1000));
  else std::snprintf(text, sizeof text, "%.1f s", double(ms) / 1000.0);
  return text;
}

// The options' identity, else ROBODIFF_DDS_SECURITY's, else none.
dds_codec::DdsSecurity securityOf(const DdsConnectionOptions& options) {
  if (options.security.enabled()) return options.security;
  const char* spec = std::getenv("ROBODIFF_DDS_SECURITY");
  if (spec == nullptr || *spec == '\0') return {};
  try {
    return dds_codec::securityFromSpec(spec);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("ROBODIFF_DDS_SECURITY: ") + e.what());
  }
}

}  // namespace

DdsConnection::DdsConnection(DdsConnectionOptions options)
    : options_(std::move(options)), pending_(std::make_unique<PendingCalls>()) {
  client_id_ = options_.connection.client_id.empty() ? defaultClientId() : options_.connection.client_id;
  endpoints_ = std::make_unique<dds_codec::DdsEndpoints>(options_.domain_id, options_.service_name,
                                                         dds_codec::DdsEndpoints::Side::Client,
                                                         std::chrono::seconds(1), options_.lease,
                                                         securityOf(options_));
  guard_ = dds_create_guardcondition(endpoints_->participant());
  if (guard_ < 0) throw std::runtime_error(dds_codec::ddsError("dds_create_guardcondition", guard_));
  // The status conditions that report a server (dis)appearing.
  dds_set_status_mask(endpoints_->writer(), DDS_PUBLICATION_MATCHED_STATUS);
  dds_set_status_mask(endpoints_->reader(), DDS_SUBSCRIPTION_MATCHED_STATUS);
  receiver_ = std::thread([this] { receiveLoop(); });
}

DdsConnection::~DdsConnection() {
  stopping_ = true;
  dds_set_guardcondition(guard_, true);
  if (receiver_.joinable()) receiver_.join();
  pending_->close(StatusCode::Cancelled, "the DDS connection was closed");
  endpoints_.reset();
}

std::uint32_t DdsConnection::domainId() const { return endpoints_->domainId(); }

bool DdsConnection::connected() const {
  std::lock_guard lock(match_mutex_);
  return matched_;
}

// ---- the receive thread ------------------------------------------------------------------

void DdsConnection::receiveLoop() {
  const dds_entity_t participant = endpoints_->participant(), reader = endpoints_->reader();
  const dds_entity_t waitset = dds_create_waitset(participant);
  const dds_entity_t readable = dds_create_readcondition(reader, DDS_ANY_STATE);
  dds_waitset_attach(waitset, readable, 0);
  dds_waitset_attach(waitset, guard_, 0);
  dds_waitset_attach(waitset, endpoints_->writer(), 0);  // publication matched
  dds_waitset_attach(waitset, reader, 0);                // subscription matched
  updateMatched();
  while (!stopping_) {
    dds_waitset_wait(waitset, nullptr, 0, DDS_INFINITY);
    takeReplies();    // first: replies a server wrote just before it went away still count
    updateMatched();
  }
  dds_delete(readable);
  dds_delete(waitset);
}

void DdsConnection::takeReplies() {
  constexpr int kBatch = 16;
  void* samples[kBatch];
  dds_sample_info_t infos[kBatch];
  for (;;) {
    std::fill(std::begin(samples), std::end(samples), nullptr);  // null: loan from the reader
    const dds_return_t n = dds_take(endpoints_->reader(), samples, infos, kBatch, kBatch);
    if (n <= 0) return;
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      const auto& reply = *static_cast<const robodiff_wire_Reply*>(samples[i]);
      // Every client of our caller partition reads its replies: keep ours.
      if (reply.header.client_id && client_id_ == reply.header.client_id) pending_->deliver(reply);
    }
    dds_return_loan(endpoints_->reader(), samples, n);
  }
}

void DdsConnection::updateMatched() {
  dds_publication_matched_status_t publication{};
  dds_subscription_matched_status_t subscription{};
  dds_get_publication_matched_status(endpoints_->writer(), &publication);  // also resets the trigger
  dds_get_subscription_matched_status(endpoints_->reader(), &subscription);
  const bool now = publication.current_count > 0 && subscription.current_count > 0;
  std::lock_guard lock(match_mutex_);
  if (now == matched_) return;
  // The pending-call table changes state together with matched_, so that a caller who sees
  // matched_ can register (and one who cannot register waits for matched_).
  if (now) {
    pending_->open();
    confirmed_ = false;
  } else {
    pending_->close(StatusCode::Unavailable,
                    "robodiffd went away on DDS domain " + std::to_string(domainId()) + ", topic " +
                        endpoints_->writerTopic() + " (it stopped or crashed); retry when it is back");
  }
  matched_ = now;
  match_cv_.notify_all();
}

bool DdsConnection::waitMatched(Clock::time_point until) {
  std::unique_lock lock(match_mutex_);
  return match_cv_.wait_until(lock, until, [&] { return matched_; });
}

// Our side sees the server; until the server has seen us too, what we send (or what it
// answers) may be lost. A Health probe that is answered proves both directions; probes
// that time out are sent again until `deadline`.
Status DdsConnection::confirmServer(Clock::time_point deadline) {
  std::lock_guard lock(confirm_mutex_);
  while (!confirmed_) {
    const auto now = Clock::now();
    if (now >= deadline)
      return {StatusCode::DeadlineExceeded, "robodiffd on DDS domain " + std::to_string(domainId()) + ", topic " +
                                                endpoints_->writerTopic() +
                                                " was discovered but answered no probe before the deadline"};
    CallOptions probe;
    probe.timeout = std::min<std::chrono::nanoseconds>(options_.probe_timeout, deadline - now);
    rpc::HealthReply ignored;
    const rpc::HealthRequest request;
    const Status s = unary(UnaryCall{HealthCall{&request, &ignored}}, probe, false);
    if (s.code == StatusCode::Unavailable) return s;
    if (s.code != StatusCode::DeadlineExceeded) confirmed_ = true;  // any answer will do
  }
  return {};
}

// ---- calls -----------------------------------------------------------------------------------

Status DdsConnection::exchange(rpc::Method method, const Encode& encode, Consume consume, CallOptions options,
                               bool confirm) {
  const auto start = Clock::now();
  const auto timeout = std::chrono::duration_cast<Clock::duration>(
      options.timeout.count() > 0 ? options.timeout : options_.connection.default_timeout);
  const auto deadline = start + timeout;

  PendingCall call;
  call.method = method;
  call.consume = std::move(consume);
  const std::uint64_t id = next_correlation_id_.fetch_add(1);
  // A server must be matched first, or DDS drops the request.
  const auto match_limit = std::min(deadline, start + std::chrono::duration_cast<Clock::duration>(options_.match_timeout));
  while (!pending_->add(id, call)) {
    if (!waitMatched(match_limit))
      return {StatusCode::Unavailable, "no robodiffd answered on DDS domain " + std::to_string(domainId()) +
                                           ", topic " + endpoints_->writerTopic() + ", within " +
                                           seconds(match_limit - start) + "; is it running?"};
  }

  if (confirm && !confirmed_) {
    pending_->remove(id);
    if (Status s = confirmServer(deadline); !s.ok()) return s;
    if (!pending_->add(id, call))
      return {StatusCode::Unavailable, "robodiffd went away on DDS domain " + std::to_string(domainId()) + ", topic " +
                                           endpoints_->writerTopic() + " just after answering; retry when it is back"};
  }

  // The wire header is filled in directly (an rpc::RequestHeader would copy the client id
  // into a std::string on every call).
  dds_codec::WireRequest request;
  robodiff_wire_RequestHeader& header = request->header;
  header.schema_version.major = options_.connection.schema_version.major;
  header.schema_version.minor = options_.connection.schema_version.minor;
  header.client_id = dds_codec::dupString(client_id_);
  header.correlation_id = id;
  header.deadline_budget_ns = static_cast<std::uint64_t>(std::chrono::nanoseconds(timeout).count());
  header.server_instance_id = dds_codec::dupString(options_.connection.server_instance_id);
  dds_sequence_double* borrowed = encode(request->body);
  const dds_return_t rc = dds_write(endpoints_->writer(), &request.get());
  if (borrowed) dds_codec::detachDoubles(*borrowed);
  if (rc != DDS_RETCODE_OK) {
    pending_->remove(id);
    return {StatusCode::Unavailable, "sending the " + std::string(rpc::toString(method)) + " request: " +
                                         dds_codec::ddsError("dds_write", rc) + " (topic " +
                                         endpoints_->writerTopic() + ")"};
  }
  if (auto status = pending_->wait(id, call, deadline)) return *status;
  return {StatusCode::DeadlineExceeded, "no reply to " + std::string(rpc::toString(method)) + " within " +
                                            seconds(timeout) + " from robodiffd on DDS domain " +
                                            std::to_string(domainId()) + ", topic " + endpoints_->writerTopic()};
}

Status DdsConnection::call(const UnaryCall& unary_call, CallOptions options) {
  return unary(unary_call, options, true);
}

// A message request goes through the codec's body variant (the union member is the
// method's); the reply's discriminator must be the method's too.
Status DdsConnection::unary(const UnaryCall& unary_call, CallOptions options, bool confirm) {
  return std::visit(
      [&](const auto& c) {
        using Reply = std::remove_pointer_t<decltype(c.reply)>;
        return exchange(
            c.method,
            [&](robodiff_wire_RequestBody& body) -> dds_sequence_double* {
              dds_codec::toWire(dds_codec::RequestBody{*c.request}, body);
              return nullptr;
            },
            [&](const robodiff_wire_Reply& r, bool&) {
              dds_codec::ReplyBody decoded;
              if (Status s = dds_codec::fromWire(r.body, decoded); !s.ok())
                return Status{StatusCode::Internal, "the server's reply is unreadable: " + s.message};
              Reply* typed = std::get_if<Reply>(&decoded);
              if (typed == nullptr)
                return Status{StatusCode::Internal, "the server answered " + std::string(rpc::toString(c.method)) +
                                                        " with the reply of another method"};
              *c.reply = std::move(*typed);
              return Status{};
            },
            options, confirm);
      },
      unary_call);
}

Status DdsConnection::evaluate(std::string_view function_id, std::span<const double> inputs,
                               std::span<double> outputs, CallOptions options) {
  return exchange(
      rpc::Method::Evaluate,
      [&](robodiff_wire_RequestBody& body) -> dds_sequence_double* {
        body._d = robodiff_wire_METHOD_EVALUATE;
        body._u.evaluate.function_id = dds_codec::dupString(function_id);
        dds_codec::borrowDoubles(body._u.evaluate.inputs, inputs);  // no copy: dds_write serialises it
        return &body._u.evaluate.inputs;
      },
      [&](const robodiff_wire_Reply& r, bool&) {
        const auto values = dds_codec::view(r.body._u.evaluate.outputs);
        if (values.size() != outputs.size())
          return Status{StatusCode::Internal, "the Evaluate reply has " + std::to_string(values.size()) +
                                                  " outputs but the caller's span holds " +
                                                  std::to_string(outputs.size())};
        if (!values.empty()) std::memcpy(outputs.data(), values.data(), values.size() * sizeof(double));
        return Status{};
      },
      options);
}

Status DdsConnection::evaluateBatch(std::string_view function_id, std::uint64_t knots, std::span<const double> inputs,
                                    std::span<double> outputs, CallOptions options) {
  if (knots > UINT32_MAX)
    return {StatusCode::InvalidArgument, "EvaluateBatch of " + std::to_string(knots) +
                                             " knots: the wire format carries at most 4294967295; split the batch"};
  dds_codec::BatchAssembler assembler(knots, outputs);
  return exchange(
      rpc::Method::EvaluateBatch,
      [&](robodiff_wire_RequestBody& body) -> dds_sequence_double* {
        body._d = robodiff_wire_METHOD_EVALUATE_BATCH;
        body._u.evaluate_batch.function_id = dds_codec::dupString(function_id);
        body._u.evaluate_batch.knot_count = static_cast<std::uint32_t>(knots);
        dds_codec::borrowDoubles(body._u.evaluate_batch.inputs, inputs);
        return &body._u.evaluate_batch.inputs;
      },
      [&](const robodiff_wire_Reply& r, bool& complete) {
        Status status = assembler.add(r.body._u.evaluate_batch);
        complete = assembler.complete();
        return status;
      },
      options);
}

std::unique_ptr<Connection> connectDds(const DdsConnectionOptions& options) {
  return std::make_unique<DdsConnection>(options);
}

}  // namespace robodiff::client
