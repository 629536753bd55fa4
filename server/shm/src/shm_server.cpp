// The iceoryx transport's server: sessions, receive thread, fair lanes per session, Evaluate, posted methods.
#include "robodiff/server/shm_server.hpp"

#include <atomic>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/rpc_header.hpp"
#include "iceoryx_posh/popo/untyped_server.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "robodiff/schema/shm_codec.hpp"
#include "robodiff/schema/shm_runtime.hpp"
#include "robodiff/server/error_budget.hpp"
#include "robodiff/server/fair_scheduler.hpp"
#include "robodiff/server/shm_caller.hpp"
#include "shm_discovery.hpp"
#include "shm_sessions.hpp"

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

// The iceoryx client port a request came from (the unique id of the client's response
// queue): the key of the shared port's error budget. iceoryx keeps it protected; a
// derived type reads it.
struct ClientPortOf : iox::popo::RequestHeader {
  static std::uint64_t key(const iox::popo::RequestHeader& routing) {
    return static_cast<std::uint64_t>(routing.*(&ClientPortOf::m_uniqueClientQueueId));
  }
};

// A request taken from iceoryx, its chunk already released: iceoryx's routing header
// (moved out of the chunk: a plain copy of the client queue id, queue index and sequence
// id), the parsed header and a copy of the body (view.body points into it).
struct TakenRequest {
  TakenRequest(shm_detail::SessionPtr s, const iox::popo::RequestHeader& r)
      : session(std::move(s)), routing(std::move(const_cast<iox::popo::RequestHeader&>(r))) {}
  shm_detail::SessionPtr session;  // the port it came on, and the caller
  iox::popo::RequestHeader routing;
  shm::RequestView view;
  std::vector<std::byte> body;
  Clock::time_point received;
  mutable QuotaSlot quota;  // its place in its client's quota (fair_scheduler.hpp)
};
using Taken = std::shared_ptr<TakenRequest>;
using shm_detail::ShmSession;
using shm_detail::SessionPtr;

// How long the shared port is not drained once a sender there has spent its error
// budget: session opens behind its garbage wait at most this long.
constexpr auto kSharedPortPause = std::chrono::milliseconds(10);
constexpr auto kSweepInterval = std::chrono::milliseconds(200);  // closing sessions whose client left

}  // namespace

struct ShmServer::Impl {
  ServiceApi& service;
  ShmServerOptions options;
  Logger& log;

  std::unique_ptr<iox::popo::WaitSet<>> waitset;
  std::unique_ptr<shm_detail::ShmSessions> sessions;  // the receive thread's
  std::thread receiver;
  std::atomic<bool> running{false};
  std::atomic<bool> accepting{true};

  mutable std::mutex idle_mutex;
  std::condition_variable idle_cv;
  std::size_t in_flight = 0;

  // Fair sharing (fair_scheduler.hpp): lanes per session; bad requests budgeted.
  FairScheduler<Taken> scheduler;
  ErrorBudget malformed, refused;  // per session
  ErrorBudget shared_port_errors;  // per client port on the shared port
  Clock::time_point next_sweep{};
  std::atomic<std::size_t> open_sessions{0};  // for openSessions(), set by the receive thread

  Impl(ServiceApi& s, ShmServerOptions o, Logger& l)
      : service(s), options(std::move(o)), log(l), scheduler(options.fair),
        malformed(options.error_replies_per_second), refused(options.error_replies_per_second),
        shared_port_errors(options.error_replies_per_second) {}

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
  Status sendReply(ShmSession& session, const iox::popo::RequestHeader& routing, const rpc::RequestHeader& request,
                   rpc::Method method, Status status, std::span<const std::byte> body) {
    if (!status.ok()) body = {};
    std::uint64_t size = shm::chunkSize(shm::wireMessage(status).size(), body.size());
    if (size > options.max_chunk_payload) {
      status = tooLarge(std::string(rpc::toString(method)) + " reply", size);
      body = {};
      size = shm::chunkSize(shm::wireMessage(status).size(), 0);
    }
    const auto header = replyHeader(request, status);
    std::lock_guard lock(session.mutex);
    if (!session.port) return status;  // the session closed: its client is gone
    auto loaned = session.port->loan(&routing, static_cast<std::uint32_t>(size), shm::kChunkAlignment);
    if (loaned.has_error()) {
      log.error("shm_reply_loan_failed", {{"method", rpc::toString(method)}, {"bytes", size},
                                          {"reason", toString(loaned.get_error())}});
      return {StatusCode::ResourceExhausted, toString(loaned.get_error())};
    }
    void* chunk = loaned.value();
    shm::writeReplyHeader(chunk, header, method, body.size());
    if (!body.empty()) std::memcpy(shm::bodyOf(chunk), body.data(), body.size());
    if (session.port->send(chunk).has_error())
      log.debug("shm_reply_dropped", {{"method", rpc::toString(method)}, {"client_id", request.client_id}});
    return status;
  }
  // A queued request's reply is about to be sent: it stops counting against its client's
  // quota first, so a client waiting for each reply before the next is never refused.
  void answer(const TakenRequest& r) { scheduler.answered(r.session->key, r.quota); }

  Status sendReply(const TakenRequest& r, Status status, std::span<const std::byte> body = {}) {
    answer(r);
    return sendReply(*r.session, r.routing, r.view.header, r.view.method, std::move(status), body);
  }

  void release(ShmSession& session, const void* payload) {
    std::lock_guard lock(session.mutex);
    session.port->releaseRequest(payload);
  }

  void record(rpc::Method method, StatusCode code, Clock::time_point received) {
    service.recordRequest(kTransport, method, code, Clock::now() - received);
  }

  // ---- the receive thread: drain every port a few chunks at a time, serve in turn -----

  void receiveLoop() {
    const auto poll = std::chrono::duration_cast<Clock::duration>(options.poll_after_request);
    while (running.load()) {
      const auto due = housekeeping();
      const auto wait = std::chrono::duration_cast<std::chrono::microseconds>(due - Clock::now()).count();
      // Woken by a request, by markForDestruction() in stop(), or when a pause or a sweep is due.
      waitset->timedWait(iox::units::Duration::fromMicroseconds(std::max<std::int64_t>(wait, 0)));
      pump();
      // A client's next request often follows its reply within microseconds: poll a
      // little before sleeping again, which saves the WaitSet wake-up.
      for (auto until = Clock::now() + poll; running.load() && Clock::now() < until;) {
        if (pump()) until = Clock::now() + poll;
        else std::this_thread::yield();
      }
    }
  }

  // Resumes paused ports, closes sessions whose client left; returns when next due.
  Clock::time_point housekeeping() {
    const auto now = Clock::now();
    if (now >= next_sweep) {
      if (const std::size_t closed = sessions->sweep(now); closed > 0)
        log.info("shm_sessions_closed", {{"closed", static_cast<std::uint64_t>(closed)},
                                         {"open", static_cast<std::uint64_t>(sessions->openSessions())}});
      next_sweep = now + kSweepInterval;
      open_sessions = sessions->openSessions();
    }
    return std::min(sessions->resumeDue(now), next_sweep);
  }

  // Until nothing is left: take up to requests_per_turn chunks from every port not
  // paused, then serve one request of every session with one waiting (one round).
  // True when anything happened.
  bool pump() {
    bool any = false;
    while (running.load()) {
      bool moved = drainAll();
      for (std::size_t round = scheduler.waitingClients(); round > 0; --round) {
        auto next = scheduler.next();
        if (!next) break;
        serve(next->client, std::move(next->item));
        moved = true;
      }
      if (!moved) break;
      any = true;
    }
    return any;
  }

  bool drainAll() {
    bool taken = false;
    const auto& all = sessions->all();
    for (std::size_t i = 0; i < all.size(); ++i) {  // by index: a session open appends
      const SessionPtr session = all[i];
      if (!session->attached) continue;  // paused
      taken |= drain(session, session->shared() ? options.request_queue_capacity : options.requests_per_turn);
    }
    return taken;
  }

  // Takes up to `most` waiting requests of one port (fewer when it gets paused).
  bool drain(const SessionPtr& session, std::uint64_t most) {
    std::uint64_t taken = 0;
    while (taken < most && session->attached) {
      const void* payload = nullptr;
      {
        std::lock_guard lock(session->mutex);
        auto t = session->port->take();
        if (t.has_error()) break;
        payload = t.value();
      }
      if (session->shared()) intakeShared(*session, payload);
      else intake(session, payload);
      ++taken;
    }
    return taken > 0;
  }

  // A chunk on the shared port: a session open, else refused (a request of a client
  // library without sessions: FAILED_PRECONDITION; garbage: INVALID_ARGUMENT) within the
  // sender's error budget. A sender past it pauses the shared port briefly.
  void intakeShared(ShmSession& shared, const void* payload) {
    const auto received = Clock::now();
    const auto& routing = *iox::popo::RequestHeader::fromPayload(payload);
    shm::RequestView view;
    if (shm::parseSessionOpen(payload, payloadSize(payload), view).ok()) {
      openSession(shared, routing, view);
      return release(shared, payload);
    }
    Status s = shm::parseRequest(payload, payloadSize(payload), view);
    if (s.ok())
      s = {StatusCode::FailedPrecondition,
           "robodiffd serves iceoryx requests on a session per connection: this port (robodiff/" + options.service +
               "/rpc) only opens sessions; the client library is older than the server, update it"};
    const auto d = shared_port_errors.note(ClientPortOf::key(routing), received);
    if (d.log)
      log.warn("shm_bad_requests", {{"client_port", ClientPortOf::key(routing)}, {"count", d.count},
                                    {"dropped_unanswered", d.dropped}, {"port", "rpc"}, {"message", s.message}});
    if (d.reply) {
      sendReply(shared, routing, view.header, view.method, s, {});
      record(view.method, s.code, received);
    } else {
      sessions->pause(shared, received + kSharedPortPause);
    }
    release(shared, payload);
  }

  void openSession(ShmSession& shared, const iox::popo::RequestHeader& routing, const shm::RequestView& view) {
    SessionPtr session;
    if (sessions->openSessions() >= sessions->limits().max_sessions) sessions->sweep(Clock::now());  // any gone?
    Status s = accepting.load() ? sessions->open(view.header.client_id,
                                                 shm_detail::callerOfShmClient(view.header.client_id), session)
                                : Status{StatusCode::Unavailable, "the server is draining (shutting down)"};
    open_sessions = sessions->openSessions();
    if (s.ok())
      log.debug("shm_session_opened", {{"event", session->event}, {"client_id", view.header.client_id},
                                       {"caller", session->caller.name}});
    else
      log.warn("shm_session_refused", {{"client_id", view.header.client_id}, {"message", s.message}});
    rpc::ReplyHeader header = replyHeader(view.header, s);
    const std::string_view event = s.ok() ? std::string_view(session->event) : std::string_view();
    const std::uint64_t size = shm::chunkSize(shm::wireMessage(s).size(), event.size());
    std::lock_guard lock(shared.mutex);
    auto loaned = shared.port->loan(&routing, static_cast<std::uint32_t>(size), shm::kChunkAlignment);
    if (loaned.has_error()) return;  // the client times out; its session closes unused
    shm::writeSessionReply(loaned.value(), header, event);
    if (shared.port->send(loaned.value()).has_error()) log.debug("shm_session_reply_dropped", {{"client_id", view.header.client_id}});
  }

  // One request chunk of a session: checked, refused or copied into the session's lane;
  // always released. A session past its error budget is paused for the rest of its window.
  void intake(const SessionPtr& session, const void* payload) {
    const auto received = Clock::now();
    const auto& routing = *iox::popo::RequestHeader::fromPayload(payload);
    const std::uint64_t client = session->key;
    session->had_client = true;  // (a client that sends and leaves between two sweeps)
    shm::RequestView view;
    if (Status s = shm::parseRequest(payload, payloadSize(payload), view); !s.ok()) {
      const auto d = malformed.note(client, received);
      if (d.log)
        log.warn("shm_bad_requests", {{"session", session->event}, {"client_id", session->client_id}, {"count", d.count},
                                      {"dropped_unanswered", d.dropped}, {"message", s.message}});
      if (d.reply) {
        sendReply(*session, routing, view.header, view.method, s, {});
        record(view.method, s.code, received);
      } else {
        sessions->pause(*session, d.window_end);
      }
      return release(*session, payload);
    }
    if (!accepting.load()) {
      Status s{StatusCode::Unavailable, "the server is draining (shutting down); retry on another server"};
      return refuse(*session, payload, routing, view, std::move(s), received);
    }
    if (Status s = service.admit(view.header); !s.ok()) {
      const bool other_server = s.code == StatusCode::NotFound && !view.header.server_instance_id.empty() &&
                                view.header.server_instance_id != service.instanceId();
      if (!other_server) return refuse(*session, payload, routing, view, std::move(s), received);
      return release(*session, payload);  // not ours to answer
    }
    auto taken = std::make_shared<TakenRequest>(session, routing);
    taken->view = std::move(view);
    taken->body.assign(taken->view.body.begin(), taken->view.body.end());
    taken->view.body = taken->body;
    taken->received = received;
    release(*session, payload);
    if (scheduler.push(client, taken)) {
      taken->quota.admit();  // served on this thread, later
      begin();                 // in flight until answered (waitIdle)
    } else {
      overQuota(client, *taken);
    }
  }

  void refuse(ShmSession& session, const void* payload, const iox::popo::RequestHeader& routing,
              const shm::RequestView& view, Status s, Clock::time_point received) {
    sendReply(session, routing, view.header, view.method, s, {});
    release(session, payload);
    record(view.method, s.code, received);
  }

  // A client with max_queued requests pending: RESOURCE_EXHAUSTED, within its error
  // budget; past it, its session is paused for the rest of the budget's window.
  void overQuota(std::uint64_t client, const TakenRequest& r) {
    const auto d = refused.note(client, r.received);
    const std::uint32_t quota = scheduler.limits().max_queued;
    if (d.log)
      log.warn("shm_client_over_queue_quota", {{"session", r.session->event}, {"client_id", r.view.header.client_id},
                                               {"count", d.count}, {"dropped_unanswered", d.dropped},
                                               {"max_queued_requests_per_client", quota}});
    if (!d.reply) return sessions->pause(*r.session, d.window_end);
    Status s{StatusCode::ResourceExhausted,
             "this client has " + std::to_string(quota) +
                 " requests pending, the most one client may have (limits.max_queued_requests_per_client = " +
                 std::to_string(quota) + "); wait for replies before sending more"};
    sendReply(r, s);
    record(r.view.method, s.code, r.received);
  }

  // The next request in turn: Evaluate here, the others on the request threads.
  void serve(std::uint64_t client, Taken taken) {
    if (taken->view.method != rpc::Method::Evaluate) return post(client, std::move(taken));
    const Status s = evaluate(*taken);
    scheduler.served(client, taken->quota);
    record(taken->view.method, s.code, taken->received);
    end();
  }

  // Evaluate / EvaluateBatch: request body -> response chunk.
  Status evaluate(const TakenRequest& r) {
    const shm::RequestView& view = r.view;
    ShmSession& session = *r.session;
    const bool batch = view.method == rpc::Method::EvaluateBatch;
    auto fail = [&](Status s) { return sendReply(r, std::move(s)); };
    shm::EvaluateRequestView request;
    if (Status s = shm::decodeEvaluateRequest(view.body, request); !s.ok()) return fail(std::move(s));
    const auto ctx = CallContext::from(view.header, kTransport, r.received);
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
      std::lock_guard lock(session.mutex);
      if (!session.port) return {StatusCode::Cancelled, "the session closed"};
      auto loaned = session.port->loan(&r.routing, static_cast<std::uint32_t>(size), shm::kChunkAlignment);
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
        std::lock_guard lock(session.mutex);
        if (session.port) session.port->releaseResponse(chunk);
      }
      return fail(s);
    }
    answer(r);
    std::lock_guard lock(session.mutex);
    if (!session.port || session.port->send(chunk).has_error())
      log.debug("shm_reply_dropped", {{"method", rpc::toString(view.method)}, {"client_id", view.header.client_id}});
    return s;
  }

  // ---- posted methods: on the request threads, at most max_running per client ---------

  // Hands a request to the service's request threads, or keeps it until one of the
  // client's running requests finishes (FairScheduler::startPosted).
  void post(std::uint64_t client, Taken taken) {
    if (scheduler.startPosted(client, taken)) hand(client, std::move(taken));
  }

  void hand(std::uint64_t client, Taken taken) {
    const bool queued = service.post([this, client, taken] {
      const Status sent = runPosted(*taken);
      record(taken->view.method, sent.code, taken->received);
      finished(client, *taken);
    });
    if (queued) return;
    Status busy{StatusCode::ResourceExhausted, std::string("the server's request queue is full; ") +
                                                   rpc::toString(taken->view.method) + " refused, retry later"};
    sendReply(*taken, busy);
    record(taken->view.method, busy.code, taken->received);
    finished(client, *taken);
  }

  // One of the client's posted requests was answered: hand over its next, if any.
  void finished(std::uint64_t client, const TakenRequest& r) {
    std::optional<Taken> next = scheduler.finishPosted(client, r.quota);
    end();
    if (next) hand(client, std::move(*next));
  }

  template <class Request, class Reply>
  Status call(const TakenRequest& r, const CallContext& ctx,
              Status (ServiceApi::*method)(const CallContext&, const Request&, Reply&)) {
    Request request;
    Status s = shm::decode(r.view.body, request);
    Reply reply;
    if (s.ok()) s = (service.*method)(ctx, request, reply);
    std::vector<std::byte> body;
    if (s.ok()) body = shm::encode(reply);
    return sendReply(r, std::move(s), body);
  }

  // Runs a posted method on a request thread and sends its reply.
  Status runPosted(const TakenRequest& r) {
    if (r.view.method == rpc::Method::EvaluateBatch) return evaluate(r);
    auto ctx = CallContext::from(r.view.header, kTransport, r.received);
    ctx.caller = r.session->caller;  // fixed when the session opened (shm_caller.hpp)
    if (ctx.expired())
      return sendReply(r, {StatusCode::DeadlineExceeded, "the deadline passed while the request was queued"});
    switch (r.view.method) {
      case rpc::Method::LoadModel: return call(r, ctx, &ServiceApi::loadModel);
      case rpc::Method::GetFunction: return call(r, ctx, &ServiceApi::getFunction);
      case rpc::Method::ListFunctions: return call(r, ctx, &ServiceApi::listFunctions);
      case rpc::Method::Health: return call(r, ctx, &ServiceApi::health);
      case rpc::Method::Release: return call(r, ctx, &ServiceApi::release);
      case rpc::Method::SubmitJob: return call(r, ctx, &ServiceApi::submitJob);
      case rpc::Method::JobStatus: return call(r, ctx, &ServiceApi::jobStatus);
      case rpc::Method::CancelJob: return call(r, ctx, &ServiceApi::cancelJob);
      case rpc::Method::JobResult: return call(r, ctx, &ServiceApi::jobResult);
      case rpc::Method::QueryArtifact: return call(r, ctx, &ServiceApi::queryArtifact);
      case rpc::Method::FetchArtifactChunk: return call(r, ctx, &ServiceApi::fetchArtifactChunk);
      case rpc::Method::FleetStatus: return call(r, ctx, &ServiceApi::fleetStatus);
      default:
        return sendReply(r, {StatusCode::Unimplemented, "method not served by posting"});
    }
  }
};

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
  d.waitset = std::make_unique<iox::popo::WaitSet<>>();
  d.sessions = std::make_unique<shm_detail::ShmSessions>(d.options.service, d.options.sessions, *d.waitset);
  if (!d.sessions->openShared(d.options.request_queue_capacity)) {
    d.sessions.reset();
    d.waitset.reset();
    return {StatusCode::Internal, "could not attach the iceoryx server to a WaitSet"};
  }
  d.accepting = true;
  d.running = true;
  d.receiver = std::thread([&d] { d.receiveLoop(); });
  d.log.info("shm_server_started", {{"service", "robodiff/" + d.options.service + "/rpc"},
                                    {"max_chunk_payload", d.options.max_chunk_payload},
                                    {"max_sessions", d.options.sessions.max_sessions}});
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
  // Requests still in the lanes are not answered (their clients time out, as for those
  // still in iceoryx's queue); they no longer count as in flight.
  while (auto next = d.scheduler.next()) {
    d.scheduler.served(next->client, next->item->quota);
    d.end();
  }
  {
    // Posted tasks refer to this server: wait for them all.
    std::unique_lock lock(d.idle_mutex);
    while (!d.idle_cv.wait_for(lock, std::chrono::seconds(5), [&] { return d.in_flight == 0; }))
      d.log.warn("shm_server_stop_waiting", {{"in_flight", static_cast<std::uint64_t>(d.in_flight)}});
  }
  d.sessions->closeAll();
  d.sessions.reset();
  d.open_sessions = 0;
  d.waitset.reset();
  d.log.info("shm_server_stopped", {{"service", "robodiff/" + d.options.service + "/rpc"}});
}

std::size_t ShmServer::inFlight() const {
  std::lock_guard lock(impl_->idle_mutex);
  return impl_->in_flight;
}

bool ShmServer::running() const { return impl_->running.load(); }

std::size_t ShmServer::openSessions() const { return impl_->open_sessions.load(); }

}  // namespace robodiff::server
