// The iceoryx transport's server: receive thread, zero-copy Evaluate, posted methods.
#include "robodiff/server/shm_server.hpp"

#include <atomic>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <variant>
#include <vector>

#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/rpc_header.hpp"
#include "iceoryx_posh/popo/untyped_server.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "iceoryx_posh/runtime/service_discovery.hpp"
#include "robodiff/schema/shm_codec.hpp"
#include "robodiff/schema/shm_runtime.hpp"

namespace robodiff::server {
namespace {

constexpr std::string_view kTransport = "iceoryx";

std::uint64_t payloadSize(const void* payload) {
  return iox::mepoo::ChunkHeader::fromUserPayload(payload)->userPayloadSize();
}

const char* toString(iox::popo::AllocationError error) {
  switch (error) {
    case iox::popo::AllocationError::RUNNING_OUT_OF_CHUNKS: return "the shared-memory pool of that size is used up";
    case iox::popo::AllocationError::TOO_MANY_CHUNKS_ALLOCATED_IN_PARALLEL: return "too many replies being written at once";
    case iox::popo::AllocationError::NO_MEMPOOLS_AVAILABLE: return "no mempool is configured";
    default: return "iceoryx could not allocate the chunk";
  }
}

}  // namespace

struct ShmServer::Impl {
  ServiceApi& service;
  ShmServerOptions options;
  Logger& log;

  std::mutex port_mutex;  // the iceoryx server port is not thread-safe
  std::unique_ptr<iox::popo::UntypedServer> port;
  std::unique_ptr<iox::popo::WaitSet<>> waitset;
  std::thread receiver;
  std::atomic<bool> running{false};
  std::atomic<bool> accepting{true};

  mutable std::mutex idle_mutex;
  std::condition_variable idle_cv;
  std::size_t in_flight = 0;

  Impl(ServiceApi& s, ShmServerOptions o, Logger& l) : service(s), options(std::move(o)), log(l) {}

  void begin() {
    std::lock_guard lock(idle_mutex);
    ++in_flight;
  }
  void end() {
    std::lock_guard lock(idle_mutex);
    if (--in_flight == 0) idle_cv.notify_all();
  }

  rpc::ReplyHeader replyHeader(const rpc::RequestHeader& request, Status status) const {
    rpc::ReplyHeader header;
    header.server_instance_id = service.instanceId();
    header.client_id = request.client_id;
    header.correlation_id = request.correlation_id;
    header.status = std::move(status);
    return header;
  }

  Status tooLarge(std::string_view what, std::uint64_t bytes) const {
    return {StatusCode::ResourceExhausted, std::string(what) + " of " + std::to_string(bytes) +
                                               " bytes exceeds the iceoryx transport's limit of " +
                                               std::to_string(options.max_chunk_payload) +
                                               " bytes (the largest shared-memory pool)"};
  }

  // Loans, fills and sends a reply whose body is `body` (dropped unless status is OK).
  // A reply that would not fit becomes RESOURCE_EXHAUSTED. Returns the status sent.
  Status sendReply(const iox::popo::RequestHeader& routing, const rpc::RequestHeader& request, rpc::Method method,
                   Status status, std::span<const std::byte> body) {
    if (!status.ok()) body = {};
    std::uint64_t size = shm::chunkSize(shm::wireMessage(status).size(), body.size());
    if (size > options.max_chunk_payload) {
      status = tooLarge(std::string(rpc::toString(method)) + " reply", size);
      body = {};
      size = shm::chunkSize(shm::wireMessage(status).size(), 0);
    }
    const auto header = replyHeader(request, status);
    std::lock_guard lock(port_mutex);
    auto loaned = port->loan(&routing, static_cast<std::uint32_t>(size), shm::kChunkAlignment);
    if (loaned.has_error()) {
      log.error("shm_reply_loan_failed", {{"method", rpc::toString(method)}, {"bytes", size},
                                          {"reason", toString(loaned.get_error())}});
      return {StatusCode::ResourceExhausted, toString(loaned.get_error())};
    }
    void* chunk = loaned.value();
    shm::writeReplyHeader(chunk, header, method, body.size());
    if (!body.empty()) std::memcpy(shm::bodyOf(chunk), body.data(), body.size());
    if (port->send(chunk).has_error())
      log.debug("shm_reply_dropped", {{"method", rpc::toString(method)}, {"client_id", request.client_id}});
    return status;
  }

  void release(const void* payload) {
    std::lock_guard lock(port_mutex);
    port->releaseRequest(payload);
  }

  void record(rpc::Method method, StatusCode code, Clock::time_point received) {
    service.recordRequest(kTransport, method, code, Clock::now() - received);
  }

  // Takes and handles one request; false when none is waiting.
  bool takeOne() {
    const void* payload = nullptr;
    {
      std::lock_guard lock(port_mutex);
      auto taken = port->take();
      if (taken.has_error()) return false;
      payload = taken.value();
    }
    handle(payload);
    return true;
  }

  void receiveLoop() {
    const auto poll = std::chrono::duration_cast<Clock::duration>(options.poll_after_request);
    while (running.load()) {
      waitset->wait();  // woken by a request, or by markForDestruction() in stop()
      while (running.load() && takeOne()) {
      }
      // A client's next request often follows its reply within microseconds: poll a
      // little before sleeping again, which saves the WaitSet wake-up.
      for (auto until = Clock::now() + poll; running.load() && Clock::now() < until;) {
        if (takeOne()) until = Clock::now() + poll;
        else std::this_thread::yield();
      }
    }
  }

  void handle(const void* payload) {
    const auto received = Clock::now();
    const auto& routing = *iox::popo::RequestHeader::fromPayload(payload);
    shm::RequestView view;
    if (Status s = shm::parseRequest(payload, payloadSize(payload), view); !s.ok()) {
      log.warn("shm_bad_request", {{"message", s.message}});
      sendReply(routing, view.header, view.method, s, {});
      release(payload);
      record(view.method, s.code, received);
      return;
    }
    if (!accepting.load()) {
      Status s{StatusCode::Unavailable, "the server is draining (shutting down); retry on another server"};
      sendReply(routing, view.header, view.method, s, {});
      release(payload);
      record(view.method, s.code, received);
      return;
    }
    if (Status s = service.admit(view.header); !s.ok()) {
      const bool other_server = s.code == StatusCode::NotFound && !view.header.server_instance_id.empty() &&
                                view.header.server_instance_id != service.instanceId();
      if (!other_server) sendReply(routing, view.header, view.method, s, {});  // else: not ours to answer
      release(payload);
      if (!other_server) record(view.method, s.code, received);
      return;
    }
    if (view.method == rpc::Method::EvaluateBatch) {
      postBatch(payload, routing, std::move(view), received);
      return;
    }
    if (view.method == rpc::Method::Evaluate) {
      begin();
      const Status s = evaluate(routing, view, received);
      release(payload);
      record(view.method, s.code, received);
      end();
      return;
    }
    post(payload, routing, std::move(view), received);
  }

  // Evaluate / EvaluateBatch on this thread, request chunk -> response chunk.
  Status evaluate(const iox::popo::RequestHeader& routing, const shm::RequestView& view,
                  Clock::time_point received) {
    const bool batch = view.method == rpc::Method::EvaluateBatch;
    auto fail = [&](Status s) { return sendReply(routing, view.header, view.method, std::move(s), {}); };
    shm::EvaluateRequestView request;
    if (Status s = shm::decodeEvaluateRequest(view.body, request); !s.ok()) return fail(std::move(s));
    const auto ctx = CallContext::from(view.header, kTransport, received);
    if (ctx.expired()) return fail({StatusCode::DeadlineExceeded, "the deadline passed before evaluation started"});
    FunctionShape shape;
    if (Status s = service.shape(request.function_id, shape); !s.ok()) return fail(std::move(s));
    if (!batch && request.knots != 1)
      return fail({StatusCode::InvalidArgument, "an Evaluate request carries one knot, not " + std::to_string(request.knots)});
    if (batch && request.knots > shape.max_batch_knots)
      return fail({StatusCode::ResourceExhausted, "a batch of " + std::to_string(request.knots) +
                                                      " knots exceeds this function's limit of " +
                                                      std::to_string(shape.max_batch_knots) + " knots"});
    if (batch && request.knots > std::numeric_limits<std::uint32_t>::max())
      return fail({StatusCode::InvalidArgument, "knot count " + std::to_string(request.knots) + " does not fit 32 bits"});
    const std::uint64_t values = request.knots * shape.output_count;
    const std::uint64_t size = shm::chunkSize(0, shm::evaluateReplyBodySize(values));
    if (size > options.max_chunk_payload) {
      const std::uint64_t fit = (options.max_chunk_payload - shm::chunkSize(0, shm::evaluateReplyBodySize(0))) /
                                (std::max<std::uint64_t>(shape.output_count, 1) * sizeof(double));
      return fail({StatusCode::ResourceExhausted,
                   "the reply to " + std::to_string(request.knots) + " knots x " + std::to_string(shape.output_count) +
                       " outputs (" + std::to_string(size) + " bytes) exceeds the iceoryx transport's limit of " +
                       std::to_string(options.max_chunk_payload) + " bytes; send at most " + std::to_string(fit) +
                       " knots per batch"});
    }
    void* chunk = nullptr;
    {
      std::lock_guard lock(port_mutex);
      auto loaned = port->loan(&routing, static_cast<std::uint32_t>(size), shm::kChunkAlignment);
      if (loaned.has_error()) {
        const char* reason = toString(loaned.get_error());
        log.error("shm_reply_loan_failed", {{"method", rpc::toString(view.method)}, {"bytes", size}, {"reason", reason}});
        return {StatusCode::ResourceExhausted, reason};  // no chunk for an error reply either
      }
      chunk = loaned.value();
    }
    shm::writeReplyHeader(chunk, replyHeader(view.header, {}), view.method, shm::evaluateReplyBodySize(values));
    shm::EvaluateReplyFixed fixed;
    fixed.total_knots = fixed.knot_count = static_cast<std::uint32_t>(request.knots);
    fixed.value_count = values;
    const std::span<double> outputs = shm::writeEvaluateReplyBody(shm::bodyOf(chunk), fixed);
    const Status s = batch ? service.evaluateBatch(ctx, request.function_id, request.knots, request.inputs, outputs)
                           : service.evaluate(ctx, request.function_id, request.inputs, outputs);
    if (!s.ok()) {
      {
        std::lock_guard lock(port_mutex);
        port->releaseResponse(chunk);
      }
      return fail(s);
    }
    std::lock_guard lock(port_mutex);
    if (port->send(chunk).has_error())
      log.debug("shm_reply_dropped", {{"method", rpc::toString(view.method)}, {"client_id", view.header.client_id}});
    return s;
  }

  // A decoded request of a posted method, with what is needed to reply once the request
  // chunk is released: iceoryx's routing header (moved out of the chunk: a plain copy of
  // the client queue id, queue index and sequence id).
  struct Posted {
    explicit Posted(const iox::popo::RequestHeader& r)
        : routing(std::move(const_cast<iox::popo::RequestHeader&>(r))) {}
    iox::popo::RequestHeader routing;
    rpc::RequestHeader header;
    rpc::Method method = rpc::Method::Health;
    Clock::time_point received;
    std::variant<rpc::LoadModelRequest, rpc::GetFunctionRequest, rpc::ListFunctionsRequest, rpc::HealthRequest,
                 rpc::ReleaseRequest, rpc::SubmitJobRequest, rpc::JobStatusRequest, rpc::CancelJobRequest,
                 rpc::JobResultRequest>
        request;
  };

  template <class Request>
  Status decodeInto(Posted& posted, std::span<const std::byte> body) {
    Request request;
    Status s = shm::decode(body, request);
    posted.request = std::move(request);
    return s;
  }

  void post(const void* payload, const iox::popo::RequestHeader& routing, shm::RequestView view,
            Clock::time_point received) {
    auto posted = std::make_shared<Posted>(routing);
    posted->header = std::move(view.header);
    posted->method = view.method;
    posted->received = received;
    Status s;
    switch (view.method) {
      case rpc::Method::LoadModel: s = decodeInto<rpc::LoadModelRequest>(*posted, view.body); break;
      case rpc::Method::GetFunction: s = decodeInto<rpc::GetFunctionRequest>(*posted, view.body); break;
      case rpc::Method::ListFunctions: s = decodeInto<rpc::ListFunctionsRequest>(*posted, view.body); break;
      case rpc::Method::Health: s = decodeInto<rpc::HealthRequest>(*posted, view.body); break;
      case rpc::Method::Release: s = decodeInto<rpc::ReleaseRequest>(*posted, view.body); break;
      case rpc::Method::SubmitJob: s = decodeInto<rpc::SubmitJobRequest>(*posted, view.body); break;
      case rpc::Method::JobStatus: s = decodeInto<rpc::JobStatusRequest>(*posted, view.body); break;
      case rpc::Method::CancelJob: s = decodeInto<rpc::CancelJobRequest>(*posted, view.body); break;
      case rpc::Method::JobResult: s = decodeInto<rpc::JobResultRequest>(*posted, view.body); break;
      default: s = {StatusCode::Unimplemented, "method not served by posting"}; break;
    }
    release(payload);  // everything needed is in `posted` now
    if (!s.ok()) {
      sendReply(posted->routing, posted->header, posted->method, s, {});
      record(posted->method, s.code, received);
      return;
    }
    begin();
    const bool queued = service.post([this, posted] {
      const Status sent = run(*posted);
      record(posted->method, sent.code, posted->received);
      end();
    });
    if (!queued) {
      end();
      Status busy{StatusCode::ResourceExhausted, std::string("the server's request queue is full; ") +
                                                     rpc::toString(posted->method) + " refused, retry later"};
      sendReply(posted->routing, posted->header, posted->method, busy, {});
      record(posted->method, busy.code, received);
    }
  }

  // EvaluateBatch runs on a request thread (a long batch must not hold up other clients'
  // Evaluate calls on the receive thread). iceoryx lets a server hold 4 request chunks at
  // once: up to kHeldBatches batches keep theirs (inputs read in place, no copy); beyond
  // that a batch's request is copied and its chunk released, so the receive thread can
  // always take the next request.
  static constexpr int kHeldBatches = 2;
  std::atomic<int> held_batches{0};

  void postBatch(const void* payload, const iox::popo::RequestHeader& routing, shm::RequestView view,
                 Clock::time_point received) {
    struct Batch {
      std::shared_ptr<iox::popo::RequestHeader> routing_copy;  // set when the chunk was released
      std::vector<std::byte> copy;                             // the request, when copied
      const void* payload = nullptr;                           // the held chunk, otherwise
      shm::RequestView view;
    };
    auto batch = std::make_shared<Batch>();
    if (held_batches.fetch_add(1) < kHeldBatches) {
      batch->payload = payload;
      batch->view = std::move(view);
    } else {
      held_batches.fetch_sub(1);
      const auto* bytes = static_cast<const std::byte*>(payload);
      batch->copy.assign(bytes, bytes + payloadSize(payload));
      batch->routing_copy = std::make_shared<iox::popo::RequestHeader>(
          std::move(const_cast<iox::popo::RequestHeader&>(routing)));
      const Status parsed = shm::parseRequest(batch->copy.data(), batch->copy.size(), batch->view);
      release(payload);
      if (!parsed.ok()) {  // cannot happen: the chunk parsed a moment ago
        sendReply(*batch->routing_copy, batch->view.header, rpc::Method::EvaluateBatch, parsed, {});
        record(rpc::Method::EvaluateBatch, parsed.code, received);
        return;
      }
    }
    auto routingOf = [batch] () -> const iox::popo::RequestHeader& {
      return batch->routing_copy ? *batch->routing_copy : *iox::popo::RequestHeader::fromPayload(batch->payload);
    };
    auto finish = [this, batch] {
      if (batch->payload != nullptr) {
        release(batch->payload);
        held_batches.fetch_sub(1);
      }
    };
    begin();
    const bool queued = service.post([this, batch, routingOf, finish, received] {
      const Status s = evaluate(routingOf(), batch->view, received);
      finish();
      record(rpc::Method::EvaluateBatch, s.code, received);
      end();
    });
    if (!queued) {
      Status busy{StatusCode::ResourceExhausted, "the server's request queue is full; EvaluateBatch refused, retry later"};
      sendReply(routingOf(), batch->view.header, rpc::Method::EvaluateBatch, busy, {});
      finish();
      record(rpc::Method::EvaluateBatch, busy.code, received);
      end();
    }
  }

  // Runs a posted method on a request thread and sends its reply.
  Status run(Posted& posted) {
    const auto ctx = CallContext::from(posted.header, kTransport, posted.received);
    if (ctx.expired())
      return sendReply(posted.routing, posted.header, posted.method,
                       {StatusCode::DeadlineExceeded, "the deadline passed while the request was queued"}, {});
    auto call = [&](auto& request, auto reply, auto method) {
      Status s = (service.*method)(ctx, request, reply);
      std::vector<std::byte> body;
      if (s.ok()) body = shm::encode(reply);
      return sendReply(posted.routing, posted.header, posted.method, std::move(s), body);
    };
    return std::visit(
        [&](auto& request) -> Status {
          using T = std::decay_t<decltype(request)>;
          if constexpr (std::is_same_v<T, rpc::LoadModelRequest>) return call(request, rpc::LoadModelReply{}, &ServiceApi::loadModel);
          else if constexpr (std::is_same_v<T, rpc::GetFunctionRequest>) return call(request, rpc::GetFunctionReply{}, &ServiceApi::getFunction);
          else if constexpr (std::is_same_v<T, rpc::ListFunctionsRequest>) return call(request, rpc::ListFunctionsReply{}, &ServiceApi::listFunctions);
          else if constexpr (std::is_same_v<T, rpc::HealthRequest>) return call(request, rpc::HealthReply{}, &ServiceApi::health);
          else if constexpr (std::is_same_v<T, rpc::ReleaseRequest>) return call(request, rpc::ReleaseReply{}, &ServiceApi::release);
          else if constexpr (std::is_same_v<T, rpc::SubmitJobRequest>) return call(request, rpc::SubmitJobReply{}, &ServiceApi::submitJob);
          else if constexpr (std::is_same_v<T, rpc::JobStatusRequest>) return call(request, rpc::JobStatusReply{}, &ServiceApi::jobStatus);
          else if constexpr (std::is_same_v<T, rpc::CancelJobRequest>) return call(request, rpc::CancelJobReply{}, &ServiceApi::cancelJob);
          else return call(request, rpc::JobResultReply{}, &ServiceApi::jobResult);
        },
        posted.request);
  }
};

namespace {

// Whether some process offers `description` as a server (request/response).
bool serviceOffered(iox::runtime::ServiceDiscovery& discovery, const iox::capro::ServiceDescription& description) {
  bool found = false;
  discovery.findService(description.getServiceIDString(), description.getInstanceIDString(),
                        description.getEventIDString(), [&](const iox::capro::ServiceDescription&) { found = true; },
                        iox::popo::MessagingPattern::REQ_RES);
  return found;
}

// True once nobody offers `description` (at once when nobody does), false after `wait`.
bool waitForServiceFree(const iox::capro::ServiceDescription& description, std::chrono::milliseconds wait) {
  iox::runtime::ServiceDiscovery discovery;
  const auto until = std::chrono::steady_clock::now() + wait;
  while (serviceOffered(discovery, description)) {
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

}  // namespace

ShmServer::ShmServer(ServiceApi& service, ShmServerOptions options, Logger& log)
    : impl_(std::make_unique<Impl>(service, std::move(options), log)) {}

ShmServer::~ShmServer() { stop(); }

Status ShmServer::start() {
  auto& d = *impl_;
  if (d.running.load()) return {};
  if (d.options.service.empty() || d.options.service.size() > iox::capro::IdString_t::capacity())
    return {StatusCode::InvalidArgument, "iceoryx service name '" + d.options.service + "' must have 1 to " +
                                             std::to_string(iox::capro::IdString_t::capacity()) + " characters"};
  if (Status s = shm::ensureRuntime("robodiffd"); !s.ok()) return s;
  iox::popo::ServerOptions server_options;
  server_options.requestQueueCapacity =
      std::clamp<std::uint64_t>(d.options.request_queue_capacity, 1, iox::MAX_REQUEST_QUEUE_CAPACITY);
  const iox::capro::ServiceDescription description(
      "robodiff", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, d.options.service.c_str()), "rpc");
  // RouDi allows one server per service and aborts a process asking for a second one.
  // A server still registered is either alive (another robodiffd) or a crashed one RouDi
  // has not removed yet (it does within ~1.5 s): wait that long, then refuse clearly.
  if (!waitForServiceFree(description, d.options.previous_server_wait))
    return {StatusCode::AlreadyExists,
            "iceoryx service 'robodiff/" + d.options.service +
                "/rpc' is already offered on this host (another robodiffd is running, or a crashed one "
                "has not been cleaned up by RouDi); stop it or choose another name with iceoryx.service"};
  d.port = std::make_unique<iox::popo::UntypedServer>(description, server_options);
  d.waitset = std::make_unique<iox::popo::WaitSet<>>();
  if (d.waitset->attachState(*d.port, iox::popo::ServerState::HAS_REQUEST).has_error()) {
    d.waitset.reset();
    d.port.reset();
    return {StatusCode::Internal, "could not attach the iceoryx server to a WaitSet"};
  }
  d.accepting = true;
  d.running = true;
  d.receiver = std::thread([&d] { d.receiveLoop(); });
  d.log.info("shm_server_started", {{"service", "robodiff/" + d.options.service + "/rpc"},
                                    {"max_chunk_payload", d.options.max_chunk_payload}});
  return {};
}

void ShmServer::stopAccepting() { impl_->accepting = false; }

bool ShmServer::waitIdle(std::chrono::milliseconds timeout) {
  std::unique_lock lock(impl_->idle_mutex);
  return impl_->idle_cv.wait_for(lock, timeout, [&] { return impl_->in_flight == 0; });
}

void ShmServer::stop() {
  auto& d = *impl_;
  if (!d.running.exchange(false)) return;
  d.waitset->markForDestruction();
  if (d.receiver.joinable()) d.receiver.join();
  {
    // Posted tasks refer to this server: wait for them all.
    std::unique_lock lock(d.idle_mutex);
    while (!d.idle_cv.wait_for(lock, std::chrono::seconds(5), [&] { return d.in_flight == 0; }))
      d.log.warn("shm_server_stop_waiting", {{"in_flight", static_cast<std::uint64_t>(d.in_flight)}});
  }
  std::lock_guard lock(d.port_mutex);
  d.waitset.reset();
  d.port.reset();
  d.log.info("shm_server_stopped", {{"service", "robodiff/" + d.options.service + "/rpc"}});
}

std::size_t ShmServer::inFlight() const {
  std::lock_guard lock(impl_->idle_mutex);
  return impl_->in_flight;
}

bool ShmServer::running() const { return impl_->running.load(); }

}  // namespace robodiff::server
