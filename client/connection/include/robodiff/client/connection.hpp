#pragma once
// The client side of a transport: one connection to one robodiffd, over iceoryx shared
// memory (connectShm, shm_connection.hpp) or Cyclone DDS (connectDds, dds_connection.hpp).
// The controller-facing API (issue 6) is built on this; the service tests use it directly.
//
// Every call returns the server's status (or one made here: UNAVAILABLE when no server
// answers, DEADLINE_EXCEEDED when the call's timeout passes without a reply); the reply
// is only meaningful when the status is OK. Calls are thread-safe: several threads may
// share a connection, each call waits for its own reply (matched by correlation id).

#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "robodiff/schema/messages.hpp"

namespace robodiff::client {

struct CallOptions {
  // 0 = wait as long as the connection's default_timeout. Sent to the server as the
  // request's deadline budget, and enforced here too.
  std::chrono::nanoseconds timeout{0};
};

struct ConnectionOptions {
  std::string client_id;                 // empty: "<host>:<pid>:<random>"
  std::string server_instance_id;        // empty: any server
  std::chrono::nanoseconds default_timeout = std::chrono::seconds(30);
  // Sent in every request header. Only tests change it (to check the server refuses an
  // incompatible client).
  rpc::SchemaVersion schema_version;
};

class Connection {
 public:
  virtual ~Connection() = default;

  virtual std::string_view transport() const = 0;  // "iceoryx", "dds"

  virtual Status loadModel(const rpc::LoadModelRequest& request, rpc::LoadModelReply& reply,
                           CallOptions options = {}) = 0;
  virtual Status getFunction(const rpc::GetFunctionRequest& request, rpc::GetFunctionReply& reply,
                             CallOptions options = {}) = 0;
  virtual Status listFunctions(const rpc::ListFunctionsRequest& request, rpc::ListFunctionsReply& reply,
                               CallOptions options = {}) = 0;
  virtual Status health(const rpc::HealthRequest& request, rpc::HealthReply& reply, CallOptions options = {}) = 0;
  virtual Status release(const rpc::ReleaseRequest& request, rpc::ReleaseReply& reply, CallOptions options = {}) = 0;
  // Jobs: batch work run by the server in its worker processes.
  virtual Status submitJob(const rpc::SubmitJobRequest& request, rpc::SubmitJobReply& reply,
                           CallOptions options = {}) = 0;
  virtual Status jobStatus(const rpc::JobStatusRequest& request, rpc::JobStatusReply& reply,
                           CallOptions options = {}) = 0;
  virtual Status cancelJob(const rpc::CancelJobRequest& request, rpc::CancelJobReply& reply,
                           CallOptions options = {}) = 0;
  virtual Status jobResult(const rpc::JobResultRequest& request, rpc::JobResultReply& reply,
                           CallOptions options = {}) = 0;

  // Inputs: the concatenated input blocks of one knot; outputs: room for the concatenated
  // output blocks. Sizes are not checked here (the server checks them and says what is
  // wrong), except that a reply that does not fit `outputs` is INTERNAL.
  virtual Status evaluate(std::string_view function_id, std::span<const double> inputs,
                          std::span<double> outputs, CallOptions options = {}) = 0;
  // knots knots, one after another, in and out. The reply may come in chunks; they are
  // put in place here.
  virtual Status evaluateBatch(std::string_view function_id, std::uint64_t knots, std::span<const double> inputs,
                               std::span<double> outputs, CallOptions options = {}) = 0;
};

// ListFunctions page after page (from request.page_token, usually empty) until the last:
// every function in `functions`, in order of creation. The first failing page's status.
Status listAllFunctions(Connection& connection, const rpc::ListFunctionsRequest& request,
                        std::vector<rpc::FunctionSummary>& functions, CallOptions options = {});

// "<host>:<pid>:<8 random hex digits>".
std::string defaultClientId();

}  // namespace robodiff::client
