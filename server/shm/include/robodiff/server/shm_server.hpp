#pragma once
// The iceoryx transport's server: requests arrive as shared-memory chunks (shm_codec.hpp)
// on each connection's own iceoryx service (a session); replies go back the same way.
//
// A client connection first opens a session on the shared port (a SessionOpen chunk,
// shm_codec.hpp); the server creates an iceoryx server for it on ("robodiff", service,
// "rpc.<n>.<random>"), up to sessions.max_sessions, and the connection sends everything
// else there. The shared port answers anything but a session open with an error. A
// session is closed when its client port goes (disconnect, or RouDi removing a dead
// process's ports) or when none connects within sessions.connect_grace. The session's
// caller is fixed at open (shm_caller.hpp).
//
// One receive thread waits on a WaitSet and takes at most requests_per_turn chunks from
// each session in turn into one lane per session (fair_scheduler.hpp), then serves one
// request per session in turn; a session whose error budget is spent is not drained for
// the rest of the budget's second (its queue fills, its sender waits):
//  - a request that does not parse costs its take and release: at most
//    error_replies_per_second error replies per client (the rest are dropped unanswered)
//    and one log line per client per second (error_budget.hpp);
//  - admit(); a client with fair.max_queued requests pending is refused RESOURCE_EXHAUSTED;
//  - the body is copied and the chunk released at once (iceoryx lets a server hold only 4
//    request chunks), so the receive thread can always take the next request;
//  - Evaluate on the receive thread: shape() -> size check -> loan a response of the exact
//    size -> evaluate() writing the response chunk -> send;
//  - the other methods (EvaluateBatch too) on the service's request threads through
//    post(), at most fair.max_running per client at once (the client's next ones wait in
//    its turn); a full service queue is RESOURCE_EXHAUSTED.
// Ports are not thread-safe: every loan / send / take / release holds its session's mutex.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "robodiff/schema/shm_mempools.hpp"
#include "robodiff/server/fair_scheduler.hpp"
#include "robodiff/server/log.hpp"
#include "robodiff/server/service_api.hpp"
#include "robodiff/server/shm_roudi.hpp"  // ensureRoudi(): a RouDi for the server, before start()

namespace robodiff::server {

// Sessions: every client connection opens one on the shared port and then sends its
// requests on its own iceoryx service, with its own request queue (shm_sessions.hpp).
struct ShmSessionLimits {
  std::uint32_t max_sessions = 64;  // open at once (limits.max_shm_sessions); more: RESOURCE_EXHAUSTED
  // A session's iceoryx request queue: a client of the library has at most 16 requests in
  // flight; a fuller queue makes only its own sender wait.
  std::uint64_t queue_capacity = 16;
  std::chrono::milliseconds connect_grace{5000};  // a session no client connects to is closed after this
};

struct ShmServerOptions {
  std::string service = "robodiff";        // the iceoryx instance: ("robodiff", service, "rpc")
  // The shared port's queue (session opens; max 1024); sessions have their own (sessions).
  std::uint64_t request_queue_capacity = 64;
  ShmSessionLimits sessions;
  // Chunks taken from one session per turn before the next session's.
  std::uint64_t requests_per_turn = 4;
  // Requests and replies above this many bytes are RESOURCE_EXHAUSTED (never loaned).
  std::uint64_t max_chunk_payload = shm::maxChunkPayload();
  // After a burst of requests the receive thread polls this long before it sleeps on the
  // WaitSet (a controller's next call often comes microseconds after its reply; polling
  // saves a wake-up). 0: never poll. Costs up to this much CPU per burst.
  std::chrono::microseconds poll_after_request{50};
  // RouDi allows one server per service. When one is still registered at start() (a
  // crashed robodiffd RouDi has not removed yet: it takes ~1.5 s), wait this long for it
  // to go before refusing with ALREADY_EXISTS.
  std::chrono::milliseconds previous_server_wait{4000};
  // Per client port: requests pending and posted requests running at once (limits.*).
  FairLimits fair;
  // Error replies per client per second to malformed or over-quota requests; the rest
  // are dropped unanswered.
  std::uint32_t error_replies_per_second = 100;
};

class ShmServer {
 public:
  ShmServer(ServiceApi& service, ShmServerOptions options, Logger& log);
  ~ShmServer();  // stop()
  ShmServer(const ShmServer&) = delete;
  ShmServer& operator=(const ShmServer&) = delete;

  // Registers with RouDi (ensureRuntime: UNAVAILABLE at once when none runs), offers the
  // service and starts the receive thread.
  Status start();
  // Draining: new requests are answered UNAVAILABLE; those in flight finish.
  void stopAccepting();
  // Waits until no request is in flight; false on timeout.
  bool waitIdle(std::chrono::milliseconds timeout);
  // Stops the receive thread, waits for in-flight requests, stops offering. Idempotent.
  void stop();

  // Requests taken and not yet answered (in a client's lane, an Evaluate on the receive
  // thread, posted tasks).
  std::size_t inFlight() const;
  bool running() const;
  // Sessions open (as of the receive thread's last open or sweep).
  std::size_t openSessions() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace robodiff::server
