#pragma once
// The client side of the Cyclone DDS transport: a participant with a writer on
// "<service>_request" and a reader on "<service>_reply", and one receive thread that takes
// replies, keeps those with this connection's client id and hands each to its waiting call
// (by correlation id; EvaluateBatch chunks are put in place in the caller's outputs).
//
// - Before a request is sent, both the request writer and the reply reader must be matched
//   with a server (else DDS drops the request); a call waits for that at most match_timeout
//   (and never past its own timeout), then answers UNAVAILABLE naming the domain and topic.
// - When the server goes away (matched counts drop to 0), pending calls end UNAVAILABLE at
//   once; the next call waits for a server again.
// - A call past its timeout ends DEADLINE_EXCEEDED (the timeout is also the request's
//   deadline budget); its reply, if it comes, is dropped.
// Thread-safe: any number of threads may call at once.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "robodiff/client/connection.hpp"
#include "robodiff/schema/dds_topics.hpp"

struct robodiff_wire_Reply;
struct robodiff_wire_RequestBody;
struct dds_sequence_double;

namespace robodiff::client {

namespace dds_detail {
class PendingCalls;
}

struct DdsConnectionOptions {
  ConnectionOptions connection;
  // DDS domain; the default is the domain CYCLONEDDS_URI configures.
  std::uint32_t domain_id = dds_codec::kDefaultDomain;
  // Topics "<service_name>_request" and "<service_name>_reply".
  std::string service_name = std::string(dds_codec::kDefaultServiceName);
  // How long a call waits for a server to be discovered before UNAVAILABLE.
  std::chrono::milliseconds match_timeout = std::chrono::seconds(2);
  // This participant's DDS lease: how soon a server forgets this client after it died
  // (until then the server keeps its replies for it). 0: the configuration's (10 s).
  std::chrono::milliseconds lease = std::chrono::seconds(0);
  // After a server is (re)discovered, the first call first sends Health probes, each
  // waiting this long for its reply, until one is answered: our side seeing the server
  // does not mean the server sees us yet, and a request or reply sent before it does is
  // lost. Any reply proves both directions.
  std::chrono::milliseconds probe_timeout = std::chrono::milliseconds(250);
  // DDS Security identity (dds_codec::keystoreIdentity). None: the environment variable
  // ROBODIFF_DDS_SECURITY=<keystore>/<identity> names it, else the participant is open.
  dds_codec::DdsSecurity security;
};

class DdsConnection final : public Connection {
 public:
  // Creates the DDS entities and the receive thread (no server needed yet). Throws
  // std::runtime_error naming the DDS call and domain when DDS refuses.
  explicit DdsConnection(DdsConnectionOptions options);
  ~DdsConnection() override;
  DdsConnection(const DdsConnection&) = delete;
  DdsConnection& operator=(const DdsConnection&) = delete;

  std::string_view transport() const override { return "dds"; }
  const std::string& clientId() const { return client_id_; }
  std::uint32_t domainId() const;
  // Both endpoints matched with a server right now.
  bool connected() const;

  Status call(const UnaryCall& unary, CallOptions options) override;
  Status evaluate(std::string_view function_id, std::span<const double> inputs, std::span<double> outputs,
                  CallOptions options = {}) override;
  Status evaluateBatch(std::string_view function_id, std::uint64_t knots, std::span<const double> inputs,
                       std::span<double> outputs, CallOptions options = {}) override;

 private:
  // Fills the request body; returns a sequence that borrows the caller's doubles (detached
  // after the write), or nullptr.
  using Encode = std::function<dds_sequence_double*(robodiff_wire_RequestBody& body)>;
  using Consume = std::function<Status(const robodiff_wire_Reply& reply, bool& complete)>;
  // `confirm`: make sure the server answers at all first (confirmServer) after a (re)match.
  Status exchange(rpc::Method method, const Encode& encode, Consume consume, CallOptions options,
                  bool confirm = true);
  Status unary(const UnaryCall& unary, CallOptions options, bool confirm);
  bool waitMatched(std::chrono::steady_clock::time_point until);
  Status confirmServer(std::chrono::steady_clock::time_point deadline);
  void receiveLoop();
  void takeReplies();
  void updateMatched();

  DdsConnectionOptions options_;
  std::string client_id_;
  std::unique_ptr<dds_codec::DdsEndpoints> endpoints_;
  std::unique_ptr<dds_detail::PendingCalls> pending_;
  std::atomic<std::uint64_t> next_correlation_id_{1};

  mutable std::mutex match_mutex_;
  std::condition_variable match_cv_;
  bool matched_ = false;
  std::atomic<bool> confirmed_{false};  // a probe was answered since the last (re)match
  std::mutex confirm_mutex_;            // one probing thread at a time

  std::int32_t guard_ = 0;  // dds_entity_t: wakes the receive thread on destruction
  std::atomic<bool> stopping_{false};
  std::thread receiver_;
};

// A DDS connection (see DdsConnection); throws std::runtime_error when DDS refuses.
std::unique_ptr<Connection> connectDds(const DdsConnectionOptions& options = {});

}  // namespace robodiff::client
