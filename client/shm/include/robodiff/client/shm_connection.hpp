#pragma once
// The iceoryx transport's client: requests are written straight into loaned shared-memory
// chunks (shm_codec.hpp) and sent to this connection's session on the server. connectShm
// (or the first call, when the server came later or restarted) opens the session on the
// shared service ("robodiff", service, "rpc"), which answers with the session's own
// service ("robodiff", service, "rpc.<n>.<random>"): a request queue for this connection
// alone, so another client flooding its queue never delays ours (docs/limits.md, "Fair
// sharing"). Closing the connection disconnects the session's port; the server closes it.
//
// Thread-safe: one iceoryx client port guarded by a mutex, and a receive thread that
// hands each response chunk to the call waiting for its correlation id (the request's
// iceoryx sequence id is the correlation id too); a waiting call also polls the port
// itself for ~50 us first, which saves thread wake-ups. At most max_in_flight calls wait
// at once (iceoryx queues at most 16 responses per client) and at most 4 write requests
// at once (iceoryx's limit of loaned requests); more callers wait their turn.
//
// Statuses made here: UNAVAILABLE (no RouDi, no server offering the service, or the
// server went away mid-call; the connection opens a new session by itself when a server
// returns), RESOURCE_EXHAUSTED from the server at open (limits.max_shm_sessions reached),
// DEADLINE_EXCEEDED (no reply within the call's timeout), RESOURCE_EXHAUSTED (a request
// larger than the shared-memory limit: nothing is sent).

#include <chrono>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "robodiff/client/connection.hpp"
#include "robodiff/schema/shm_mempools.hpp"

namespace robodiff::client {

struct ShmConnectionOptions : ConnectionOptions {
  std::string service = "robodiff";            // the iceoryx instance: ("robodiff", service, "rpc")
  // connectShm waits this long for a server to offer the service; 0: do not wait.
  std::chrono::milliseconds connect_timeout{1000};
  // No server after connect_timeout: true = connectShm fails UNAVAILABLE; false = return
  // the connection anyway (calls are UNAVAILABLE until a server comes).
  bool require_server = true;
  std::uint32_t max_in_flight = 16;            // calls waiting for replies at once (1..16)
  std::uint64_t max_chunk_payload = shm::maxChunkPayload();  // larger requests: RESOURCE_EXHAUSTED
};

class ShmConnection final : public Connection {
 public:
  ~ShmConnection() override;

  std::string_view transport() const override { return "iceoryx"; }

  Status call(const UnaryCall& unary, CallOptions options) override;
  Status evaluate(std::string_view function_id, std::span<const double> inputs, std::span<double> outputs,
                  CallOptions options = {}) override;
  Status evaluateBatch(std::string_view function_id, std::uint64_t knots, std::span<const double> inputs,
                       std::span<double> outputs, CallOptions options = {}) override;

  // Whether a server currently offers the service to this client.
  bool serverConnected() const;
  const std::string& clientId() const;

  struct Impl;
  explicit ShmConnection(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
};

// Registers the process with RouDi (shared runtime: ensureRuntime) and creates the client
// port. Fails fast: UNAVAILABLE at once without a RouDi, after connect_timeout without a
// server (when require_server); INVALID_ARGUMENT for ids or names that do not fit.
// Returns nullptr and sets `status` on failure.
std::unique_ptr<ShmConnection> connectShm(const ShmConnectionOptions& options, Status& status);

// The same, throwing ShmConnectError (with the status) on failure.
class ShmConnectError : public std::runtime_error {
 public:
  explicit ShmConnectError(Status status);
  const Status& status() const { return status_; }

 private:
  Status status_;
};
std::unique_ptr<ShmConnection> connectShm(const ShmConnectionOptions& options = {});

}  // namespace robodiff::client
