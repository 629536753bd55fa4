// The iceoryx client: a session on the server, its port, a receive thread dispatching responses to waiting calls.
#include "robodiff/client/shm_connection.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <mutex>
#include <semaphore>
#include <thread>
#include <vector>

#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/rpc_header.hpp"
#include "iceoryx_posh/popo/untyped_client.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "robodiff/schema/shm_codec.hpp"
#include "robodiff/schema/shm_runtime.hpp"

namespace robodiff::client {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

constexpr auto kSpin = 50us;  // how long a call polls for its reply before it sleeps

const char* loanError(iox::popo::AllocationError error) {
  switch (error) {
    case iox::popo::AllocationError::RUNNING_OUT_OF_CHUNKS: return "the shared-memory pool of that size is used up";
    case iox::popo::AllocationError::TOO_MANY_CHUNKS_ALLOCATED_IN_PARALLEL: return "too many requests being written at once";
    case iox::popo::AllocationError::NO_MEMPOOLS_AVAILABLE: return "RouDi has no mempool";
    default: return "iceoryx could not allocate it";
  }
}

std::string serviceName(const std::string& service) { return "robodiff/" + service + "/rpc"; }

iox::popo::ClientOptions clientOptions() {
  iox::popo::ClientOptions options;
  options.responseQueueCapacity = iox::MAX_RESPONSE_QUEUE_CAPACITY;
  // robodiffd's request queues block a sender while full (never drop another request);
  // it accepts only clients that wait (server/shm: fair sharing).
  options.serverTooSlowPolicy = iox::popo::ConsumerTooSlowPolicy::WAIT_FOR_CONSUMER;
  return options;
}

iox::capro::ServiceDescription describe(const std::string& service, const std::string& event) {
  return {"robodiff", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service.c_str()),
          iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event.c_str())};
}

// The port of this connection's session on the server (its own request queue) and the
// WaitSet the receive thread sleeps on. Replaced when the server restarts.
struct SessionPort {
  std::unique_ptr<iox::popo::UntypedClient> port;
  std::unique_ptr<iox::popo::WaitSet<>> waitset;
  ~SessionPort() {
    waitset.reset();  // detaches from the port first
    // Tells the server this client is gone (its session closes: hasClients()); iceoryx
    // 2.0 does not when it merely destroys the port.
    if (port) port->disconnect();
    port.reset();
  }
};
using SessionPortPtr = std::shared_ptr<SessionPort>;

std::string milliseconds(std::chrono::nanoseconds d) {
  return std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(d).count()) + " ms";
}

}  // namespace

struct ShmConnection::Impl {
  ShmConnectionOptions options;
  std::string client_id;
  std::atomic<std::uint64_t> next_correlation{1};

  mutable std::mutex port_mutex;  // the iceoryx client ports are not thread-safe
  SessionPortPtr session;          // null until a session is open
  // The shared port: opens sessions (under session_mutex), tells whether a server is there.
  std::unique_ptr<iox::popo::UntypedClient> hello;
  std::mutex session_mutex;        // one session open at a time
  std::thread receiver;
  std::atomic<bool> running{false};

  // Calls waiting for their reply, by correlation id.
  struct Pending {
    const void* response = nullptr;  // the response chunk, handed over by the receive thread
    SessionPortPtr from;             // the port it came from (to release it there)
    const SessionPort* sent_to = nullptr;  // the session the request went to
    std::atomic<bool> done{false};  // set under pending_mutex; read without it while spinning
    Status failure;                  // when done without a response
  };
  std::mutex pending_mutex;
  std::condition_variable pending_cv;
  // A short list (at most max_in_flight entries) in capacity reserved at connect: adding
  // and removing never allocates, so a call does not either.
  std::vector<std::pair<std::uint64_t, Pending*>> pending;

  Pending* findPending(std::uint64_t id) {  // pending_mutex held
    for (auto& [key, p] : pending)
      if (key == id) return p;
    return nullptr;
  }
  void erasePending(std::uint64_t id) {  // pending_mutex held
    for (std::size_t i = 0; i < pending.size(); ++i)
      if (pending[i].first == id) {
        pending[i] = pending.back();
        pending.pop_back();
        return;
      }
  }

  // iceoryx lets a client hold at most 4 loaned, unsent requests (bodies are written
  // outside the port mutex, so more callers could be between loan and send).
  std::counting_semaphore<iox::MAX_REQUESTS_ALLOCATED_SIMULTANEOUSLY> loans{iox::MAX_REQUESTS_ALLOCATED_SIMULTANEOUSLY};

  // At most max_in_flight calls between send and reply (iceoryx keeps 16 responses per client).
  std::mutex slot_mutex;
  std::condition_variable slot_cv;
  std::uint32_t slots_used = 0;

  static bool connected(const SessionPortPtr& s) {  // port_mutex held
    return s && s->port->getConnectionState() == iox::ConnectionState::CONNECTED;
  }
  bool connected() const {
    std::lock_guard lock(port_mutex);
    return connected(session);
  }
  // A server offers the service: the session is connected, or the shared port is.
  bool serverThere() const {
    std::lock_guard lock(port_mutex);
    return connected(session) || hello->getConnectionState() == iox::ConnectionState::CONNECTED;
  }
  SessionPortPtr currentSession() const {
    std::lock_guard lock(port_mutex);
    return session;
  }

  Status noServer() const {
    return {StatusCode::Unavailable, "no robodiff server offers iceoryx service " + serviceName(options.service) +
                                         " (is robodiffd running with iceoryx enabled?)"};
  }

  void releaseResponse(SessionPort& from, const void* response) {
    std::lock_guard lock(port_mutex);
    from.port->releaseResponse(response);
  }

  // Fails the calls waiting on session `only` (every call when null): a lost session must
  // not fail a call already sent to the session that replaced it.
  void failAll(const Status& status, const SessionPort* only = nullptr) {
    std::lock_guard lock(pending_mutex);
    bool any = false;
    for (auto& [id, p] : pending) {
      if (p->done || (only != nullptr && p->sent_to != only)) continue;
      p->done = true;
      p->failure = status;
      any = true;
    }
    if (any) pending_cv.notify_all();
  }

  void receiveLoop() {
    while (running.load()) {
      const SessionPortPtr s = currentSession();
      if (!s) {
        std::this_thread::sleep_for(20ms);
        continue;
      }
      s->waitset->timedWait(iox::units::Duration::fromMilliseconds(20));
      if (!running.load()) break;
      for (;;) {
        const void* response = nullptr;
        {
          std::lock_guard lock(port_mutex);
          auto taken = s->port->take();
          if (taken.has_error()) break;
          response = taken.value();
        }
        dispatch(s, response);
      }
      bool lost;
      {
        std::lock_guard lock(port_mutex);
        lost = session == s && !connected(s);
      }
      if (lost)
        failAll({StatusCode::Unavailable,
                 "the robodiff server went away (iceoryx service " + serviceName(options.service) + " is no longer offered)"},
                s.get());
    }
  }

  // Takes one response, if there is one and the port is free, and dispatches it.
  bool pollOnce() {
    const void* response = nullptr;
    SessionPortPtr from;
    {
      std::unique_lock lock(port_mutex, std::try_to_lock);
      if (!lock.owns_lock() || !session) return false;
      auto taken = session->port->take();
      if (taken.has_error()) return false;
      response = taken.value();
      from = session;
    }
    dispatch(from, response);
    return true;
  }

  // Hands a response to the call it answers: iceoryx gives the response the request's
  // sequence id, which is the request's correlation id.
  void dispatch(const SessionPortPtr& from, const void* response) {
    const auto id = static_cast<std::uint64_t>(iox::popo::ResponseHeader::fromPayload(response)->getSequenceId());
    {
      std::lock_guard lock(pending_mutex);
      Pending* p = findPending(id);
      if (p != nullptr && !p->done) {
        p->response = response;
        p->from = from;
        p->done = true;
        pending_cv.notify_all();
        return;
      }
    }
    releaseResponse(*from, response);  // its caller gave up (timeout)
  }

  // Opens a session on the server through the shared port (SessionOpen, shm_codec.hpp)
  // and connects its port; the connection's requests go there from then on.
  Status openSession(Clock::time_point deadline) {
    std::lock_guard opening(session_mutex);
    if (connected()) return {};  // another caller did it
    if (hello->getConnectionState() != iox::ConnectionState::CONNECTED) return noServer();
    rpc::RequestHeader header;
    header.schema_version = options.schema_version;
    header.client_id = client_id;
    header.correlation_id = next_correlation.fetch_add(1);
    header.server_instance_id = options.server_instance_id;
    auto loaned = hello->loan(static_cast<std::uint32_t>(shm::chunkSize(0, 0)), shm::kChunkAlignment);
    if (loaned.has_error())
      return {StatusCode::ResourceExhausted,
              std::string("could not loan a chunk to open an iceoryx session: ") + loanError(loaned.get_error())};
    shm::writeSessionOpen(loaned.value(), header);
    iox::popo::RequestHeader::fromPayload(loaned.value())->setSequenceId(static_cast<std::int64_t>(header.correlation_id));
    if (hello->send(loaned.value()).has_error()) return noServer();
    std::string event;
    if (Status s = awaitSessionReply(header.correlation_id, deadline, event); !s.ok()) return s;
    auto fresh = std::make_shared<SessionPort>();
    fresh->port = std::make_unique<iox::popo::UntypedClient>(describe(options.service, event), clientOptions());
    fresh->waitset = std::make_unique<iox::popo::WaitSet<>>();
    if (fresh->waitset->attachState(*fresh->port, iox::popo::ClientState::HAS_RESPONSE).has_error())
      return {StatusCode::Internal, "could not attach the iceoryx client to a WaitSet"};
    while (fresh->port->getConnectionState() != iox::ConnectionState::CONNECTED) {
      if (Clock::now() >= deadline)
        return {StatusCode::Unavailable, "the robodiff server opened iceoryx session " + event +
                                             " but its port did not connect in time"};
      std::this_thread::sleep_for(200us);
    }
    std::lock_guard lock(port_mutex);
    session = std::move(fresh);  // the old one (if any) goes with the last response taken from it
    return {};
  }

  // The server's answer to our session open, read from the shared port.
  Status awaitSessionReply(std::uint64_t correlation, Clock::time_point deadline, std::string& event) {
    while (Clock::now() < deadline) {
      auto taken = hello->take();
      if (taken.has_error()) {
        std::this_thread::sleep_for(100us);
        continue;
      }
      const void* reply = taken.value();
      shm::ReplyView view;
      Status s = shm::parseSessionReply(reply, iox::mepoo::ChunkHeader::fromUserPayload(reply)->userPayloadSize(), view);
      const bool ours = s.ok() && view.header.correlation_id == correlation;
      if (ours && view.header.status.ok()) event.assign(reinterpret_cast<const char*>(view.body.data()), view.body.size());
      if (ours) s = view.header.status;
      if (!s.ok() && s.code == StatusCode::InvalidArgument && !ours)
        s = {StatusCode::FailedPrecondition, "the server does not open iceoryx sessions (" + s.message +
                                                 "): it is older than this client library"};
      hello->releaseResponse(reply);
      if (!ours && s.ok()) continue;  // an answer to an earlier open that timed out
      if (s.ok() && event.empty()) s = {StatusCode::Internal, "the server's session reply names no session"};
      return s;
    }
    return {StatusCode::Unavailable, "the robodiff server did not answer the iceoryx session open on " +
                                         serviceName(options.service) + " in time"};
  }

  // Waits until `deadline` for one of the max_in_flight slots, and takes it.
  Status takeSlot(rpc::Method method, std::chrono::nanoseconds timeout, Clock::time_point deadline) {
    std::unique_lock lock(slot_mutex);
    if (!slot_cv.wait_until(lock, deadline, [&] { return slots_used < options.max_in_flight; }))
      return {StatusCode::DeadlineExceeded, std::string(rpc::toString(method)) + ": no reply within " +
                                                milliseconds(timeout) + " (the call waited for a free slot)"};
    ++slots_used;
    return {};
  }
  struct SlotGuard {  // gives the slot back when the call ends
    Impl& d;
    ~SlotGuard() {
      std::lock_guard lock(d.slot_mutex);
      --d.slots_used;
      d.slot_cv.notify_one();
    }
  };
  struct LoanGuard {  // gives the loan slot back once the request is sent (or given up)
    Impl& d;
    bool held = true;
    void release() {
      if (held) d.loans.release();
      held = false;
    }
    ~LoanGuard() { release(); }
  };

  // A request chunk of `size` bytes loaned from the current session, and that session
  // (`to`); without one, or after a server restart, a session is opened first (once).
  Status loanRequest(std::uint64_t size, Clock::time_point deadline, void** chunk, SessionPortPtr* to) {
    for (int attempt = 0;; ++attempt) {
      {
        std::lock_guard lock(port_mutex);
        if (connected(session)) {
          auto loaned = session->port->loan(static_cast<std::uint32_t>(size), shm::kChunkAlignment);
          if (loaned.has_error())
            return {StatusCode::ResourceExhausted, "could not loan a " + std::to_string(size) +
                                                       "-byte shared-memory chunk: " + loanError(loaned.get_error()) +
                                                       "; retry later"};
          *chunk = loaned.value();
          *to = session;
          return {};
        }
      }
      if (attempt > 0) return noServer();
      if (Status s = openSession(deadline); !s.ok()) return s;
    }
  }

  // Waits until `deadline` for the reply to `correlation`. Replies usually come within
  // microseconds: the port is polled here briefly before sleeping on the condition
  // variable (saves the receive thread's wake-up and ours).
  Status awaitReply(const Pending& waiting, std::uint64_t correlation, rpc::Method method,
                    std::chrono::nanoseconds timeout, Clock::time_point deadline) {
    for (const auto spin_until = Clock::now() + kSpin; !waiting.done.load() && Clock::now() < spin_until;)
      if (!pollOnce()) std::this_thread::yield();
    std::unique_lock lock(pending_mutex);
    pending_cv.wait_until(lock, deadline, [&] { return waiting.done.load(); });
    erasePending(correlation);
    if (!waiting.done)
      return {StatusCode::DeadlineExceeded,
              std::string(rpc::toString(method)) + ": no reply from the robodiff server within " + milliseconds(timeout)};
    return {};
  }

  // The reply `waiting` received, checked to answer `header`'s request, read by
  // `on_reply` when OK; the response chunk is released.
  template <class OnReply>
  Status readReply(const Pending& waiting, const rpc::RequestHeader& header, rpc::Method method, OnReply&& on_reply) {
    const void* response = waiting.response;
    SessionPort& from = *waiting.from;
    const auto response_size = iox::mepoo::ChunkHeader::fromUserPayload(response)->userPayloadSize();
    thread_local shm::ReplyView view;  // reused, as the request header
    Status result = shm::parseReply(response, response_size, view);
    if (!result.ok()) {
      result = {StatusCode::Internal, "the server's reply is unreadable: " + result.message};
    } else if (!view.header.status.ok()) {
      result = std::move(view.header.status);  // (a refused malformed request may lack our ids)
    } else if (view.header.correlation_id != header.correlation_id || view.header.client_id != client_id ||
               view.method != method) {
      result = {StatusCode::Internal, "the server's reply does not match the request (correlation id, client id or method)"};
    } else {
      result = on_reply(view);
    }
    releaseResponse(from, response);
    return result;
  }

  // One call: loan a request of chunkSize(0, body_size) bytes, let `fill` write the body,
  // send, wait for the reply, let `on_reply` read an OK reply's body.
  template <class Fill, class OnReply>
  Status call(rpc::Method method, std::uint64_t body_size, CallOptions call_options, Fill&& fill, OnReply&& on_reply) {
    const auto timeout = call_options.timeout.count() > 0 ? call_options.timeout : options.default_timeout;
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(timeout);
    const std::uint64_t size = shm::chunkSize(0, body_size);
    if (size > options.max_chunk_payload)
      return {StatusCode::ResourceExhausted, std::string(rpc::toString(method)) + " request of " + std::to_string(size) +
                                                 " bytes exceeds the iceoryx transport's limit of " +
                                                 std::to_string(options.max_chunk_payload) +
                                                 " bytes (the largest shared-memory pool); nothing was sent"};
    if (Status s = takeSlot(method, timeout, deadline); !s.ok()) return s;
    SlotGuard slot_guard{*this};

    // Per thread and reused: assigning the same ids again keeps their strings' capacity,
    // so a call allocates nothing after this thread's first.
    thread_local rpc::RequestHeader header;
    header.schema_version = options.schema_version;
    header.client_id = client_id;
    header.correlation_id = next_correlation.fetch_add(1);
    header.deadline_budget_ns = static_cast<std::uint64_t>(timeout.count());
    header.server_instance_id = options.server_instance_id;

    loans.acquire();
    LoanGuard loan_guard{*this};
    void* chunk = nullptr;
    SessionPortPtr to;  // the session the request goes to, and its reply comes from
    if (Status s = loanRequest(size, deadline, &chunk, &to); !s.ok()) return s;
    shm::writeRequestHeader(chunk, header, method, body_size);
    fill(shm::bodyOf(chunk));
    iox::popo::RequestHeader::fromPayload(chunk)->setSequenceId(static_cast<std::int64_t>(header.correlation_id));

    Pending waiting;
    waiting.sent_to = to.get();
    {
      std::lock_guard lock(pending_mutex);
      pending.emplace_back(header.correlation_id, &waiting);
    }
    bool sent;
    {
      std::lock_guard lock(port_mutex);
      sent = !to->port->send(chunk).has_error();  // on error iceoryx releases the chunk
    }
    loan_guard.release();
    if (!sent) {
      std::lock_guard lock(pending_mutex);
      erasePending(header.correlation_id);
      return noServer();
    }
    if (Status s = awaitReply(waiting, header.correlation_id, method, timeout, deadline); !s.ok()) return s;
    if (waiting.response == nullptr) return waiting.failure;
    return readReply(waiting, header, method, on_reply);
  }

  template <class Request, class Reply>
  Status compact(rpc::Method method, const Request& request, Reply& reply, CallOptions call_options) {
    const std::vector<std::byte> body = shm::encode(request);
    return call(
        method, body.size(), call_options, [&](std::byte* out) { std::memcpy(out, body.data(), body.size()); },
        [&](const shm::ReplyView& view) {
          Status s = shm::decode(view.body, reply);
          if (!s.ok()) s = {StatusCode::Internal, "the server's reply is unreadable: " + s.message};
          return s;
        });
  }

  Status evaluate(rpc::Method method, std::string_view function_id, std::uint64_t knots, std::span<const double> inputs,
                  std::span<double> outputs, CallOptions call_options) {
    const std::uint64_t body_size = shm::evaluateRequestBodySize(function_id.size(), inputs.size());
    if (method == rpc::Method::EvaluateBatch) {
      if (knots > std::numeric_limits<std::uint32_t>::max())
        return {StatusCode::InvalidArgument, "a batch of " + std::to_string(knots) + " knots does not fit 32 bits"};
      const std::uint64_t size = shm::chunkSize(0, body_size);
      if (size > options.max_chunk_payload) {
        const std::uint64_t per_knot = knots == 0 ? 1 : std::max<std::uint64_t>(inputs.size() / knots, 1);
        const std::uint64_t fit =
            (options.max_chunk_payload - shm::chunkSize(0, shm::evaluateRequestBodySize(function_id.size(), 0))) /
            (per_knot * sizeof(double));
        return {StatusCode::ResourceExhausted,
                "a batch of " + std::to_string(knots) + " knots (" + std::to_string(size) +
                    " bytes) exceeds the iceoryx transport's limit of " + std::to_string(options.max_chunk_payload) +
                    " bytes (the largest shared-memory pool); nothing was sent: split it into batches of at most " +
                    std::to_string(fit) + " knots"};
      }
    }
    return call(
        method, body_size, call_options,
        [&](std::byte* body) {
          const std::span<double> in = shm::writeEvaluateRequestBody(body, function_id, knots, inputs.size());
          std::copy(inputs.begin(), inputs.end(), in.begin());
        },
        [&](const shm::ReplyView& view) -> Status {
          shm::EvaluateReplyView reply;
          if (Status s = shm::decodeEvaluateReply(view.body, reply); !s.ok())
            return {StatusCode::Internal, "the server's reply is unreadable: " + s.message};
          if (reply.fixed.chunk_count != 1 || reply.fixed.first_knot != 0)
            return {StatusCode::Internal, "split batch replies are not used over iceoryx (got chunk " +
                                              std::to_string(reply.fixed.chunk_index) + " of " +
                                              std::to_string(reply.fixed.chunk_count) + ")"};
          if (reply.outputs.size() > outputs.size())
            return {StatusCode::Internal, "the reply has " + std::to_string(reply.outputs.size()) +
                                              " outputs but the caller's buffer holds " + std::to_string(outputs.size())};
          std::copy(reply.outputs.begin(), reply.outputs.end(), outputs.begin());
          return {};
        });
  }

  ~Impl() {
    if (running.exchange(false)) {
      if (const SessionPortPtr s = currentSession()) s->waitset->markForDestruction();
      if (receiver.joinable()) receiver.join();
    }
    failAll({StatusCode::Cancelled, "the connection is closing"});
    session.reset();
    hello.reset();
  }
};

ShmConnection::ShmConnection(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShmConnection::~ShmConnection() = default;

Status ShmConnection::call(const UnaryCall& unary, CallOptions options) {
  return std::visit([&](const auto& c) { return impl_->compact(c.method, *c.request, *c.reply, options); }, unary);
}
Status ShmConnection::evaluate(std::string_view function_id, std::span<const double> inputs, std::span<double> outputs,
                               CallOptions options) {
  return impl_->evaluate(rpc::Method::Evaluate, function_id, 1, inputs, outputs, options);
}
Status ShmConnection::evaluateBatch(std::string_view function_id, std::uint64_t knots, std::span<const double> inputs,
                                    std::span<double> outputs, CallOptions options) {
  return impl_->evaluate(rpc::Method::EvaluateBatch, function_id, knots, inputs, outputs, options);
}
bool ShmConnection::serverConnected() const { return impl_->serverThere(); }
const std::string& ShmConnection::clientId() const { return impl_->client_id; }

std::unique_ptr<ShmConnection> connectShm(const ShmConnectionOptions& options, Status& status) {
  auto impl = std::make_unique<ShmConnection::Impl>();
  impl->options = options;
  impl->options.max_in_flight = std::clamp<std::uint32_t>(options.max_in_flight, 1, iox::MAX_RESPONSE_QUEUE_CAPACITY);
  impl->pending.reserve(impl->options.max_in_flight);
  impl->client_id = options.client_id;
  if (impl->client_id.empty()) {
    impl->client_id = defaultClientId();  // "<host>:<pid>:<random>": keep the unique end
    if (impl->client_id.size() >= shm::kIdCapacity)
      impl->client_id = impl->client_id.substr(impl->client_id.size() - (shm::kIdCapacity - 1));
  }
  status = shm::checkId("client id", impl->client_id);
  if (status.ok()) status = shm::checkId("server instance id", options.server_instance_id);
  if (!status.ok()) return nullptr;
  if (options.service.empty() || options.service.size() > iox::capro::IdString_t::capacity()) {
    status = {StatusCode::InvalidArgument, "iceoryx service name '" + options.service + "' must have 1 to " +
                                               std::to_string(iox::capro::IdString_t::capacity()) + " characters"};
    return nullptr;
  }
  status = shm::ensureRuntime("robodiff-client");
  if (!status.ok()) return nullptr;

  impl->hello = std::make_unique<iox::popo::UntypedClient>(describe(options.service, "rpc"), clientOptions());
  const auto until = Clock::now() + options.connect_timeout;
  while (!impl->serverThere() && Clock::now() < until) std::this_thread::sleep_for(1ms);
  if (impl->serverThere()) {
    // The session: within connect_timeout, and at least a second (the server creates a
    // port for it and RouDi connects ours).
    status = impl->openSession(std::max(until, Clock::now() + 1s));
    if (!status.ok() && options.require_server) return nullptr;
  } else if (options.require_server) {
    status = impl->noServer();
    status.message += "; waited " + milliseconds(options.connect_timeout);
    return nullptr;
  }
  impl->running = true;
  auto* d = impl.get();
  impl->receiver = std::thread([d] { d->receiveLoop(); });
  status = {};
  return std::make_unique<ShmConnection>(std::move(impl));
}

ShmConnectError::ShmConnectError(Status status)
    : std::runtime_error("iceoryx connection failed: " + toString(status.code) + ": " + status.message),
      status_(std::move(status)) {}

std::unique_ptr<ShmConnection> connectShm(const ShmConnectionOptions& options) {
  Status status;
  auto connection = connectShm(options, status);
  if (!connection) throw ShmConnectError(status);
  return connection;
}

}  // namespace robodiff::client
