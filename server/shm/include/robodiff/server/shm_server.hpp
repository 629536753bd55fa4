#pragma once
// The iceoryx transport's server: requests arrive as shared-memory chunks (shm_codec.hpp)
// on the iceoryx service ("robodiff", service, "rpc"); replies go back the same way.
//
// One receive thread waits on a WaitSet, drains iceoryx's request queue into one lane
// per client port (fair_scheduler.hpp) and serves one request per client in turn:
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
// The port is not thread-safe, so every loan / send / take / release holds one mutex.

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

struct ShmServerOptions {
  std::string service = "robodiff";        // the iceoryx instance: ("robodiff", service, "rpc")
  std::uint64_t request_queue_capacity = 256;  // chunks waiting for the receive thread (max 1024)
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

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace robodiff::server
