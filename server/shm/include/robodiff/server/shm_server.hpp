#pragma once
// The iceoryx transport's server: requests arrive as shared-memory chunks (shm_codec.hpp)
// on the iceoryx service ("robodiff", service, "rpc"); replies go back the same way.
//
// One receive thread waits on a WaitSet. Per request: validate the chunk, admit(), then
//  - Evaluate / EvaluateBatch inline on the receive thread: shape() -> size check ->
//    loan a response of the exact size -> evaluate() reading the request chunk and
//    writing the response chunk (no copy of the doubles) -> send;
//  - the other methods decoded and handed to service.post() (false: RESOURCE_EXHAUSTED at
//    once); the task encodes and sends the reply from a request thread.
// The port is not thread-safe, so every loan / send / take / release holds one mutex.
//
// iceoryx lets a server hold only 4 request chunks at once, so a posted request's chunk
// is released as soon as it is decoded (its routing header is kept): long requests (a
// GetFunction waiting for a build) never stall Evaluate.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "robodiff/schema/shm_mempools.hpp"
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

  // Requests taken and not yet answered (an Evaluate on the receive thread, posted tasks).
  std::size_t inFlight() const;
  bool running() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace robodiff::server
