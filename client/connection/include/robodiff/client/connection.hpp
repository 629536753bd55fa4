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
#include <variant>
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

// One unary call: the method, the request, and where its reply goes. Every method but
// Evaluate and EvaluateBatch is unary (those two carry spans of doubles, not messages).
template <rpc::Method M, class Request, class Reply>
struct MethodCall {
  static constexpr rpc::Method method = M;
  const Request* request;
  Reply* reply;
};
using LoadModelCall = MethodCall<rpc::Method::LoadModel, rpc::LoadModelRequest, rpc::LoadModelReply>;
using GetFunctionCall = MethodCall<rpc::Method::GetFunction, rpc::GetFunctionRequest, rpc::GetFunctionReply>;
using ListFunctionsCall = MethodCall<rpc::Method::ListFunctions, rpc::ListFunctionsRequest, rpc::ListFunctionsReply>;
using HealthCall = MethodCall<rpc::Method::Health, rpc::HealthRequest, rpc::HealthReply>;
using ReleaseCall = MethodCall<rpc::Method::Release, rpc::ReleaseRequest, rpc::ReleaseReply>;
using SubmitJobCall = MethodCall<rpc::Method::SubmitJob, rpc::SubmitJobRequest, rpc::SubmitJobReply>;
using JobStatusCall = MethodCall<rpc::Method::JobStatus, rpc::JobStatusRequest, rpc::JobStatusReply>;
using CancelJobCall = MethodCall<rpc::Method::CancelJob, rpc::CancelJobRequest, rpc::CancelJobReply>;
using JobResultCall = MethodCall<rpc::Method::JobResult, rpc::JobResultRequest, rpc::JobResultReply>;
using QueryArtifactCall = MethodCall<rpc::Method::QueryArtifact, rpc::QueryArtifactRequest, rpc::QueryArtifactReply>;
using FetchArtifactChunkCall =
    MethodCall<rpc::Method::FetchArtifactChunk, rpc::FetchArtifactChunkRequest, rpc::FetchArtifactChunkReply>;
using FleetStatusCall = MethodCall<rpc::Method::FleetStatus, rpc::FleetStatusRequest, rpc::FleetStatusReply>;
using UnaryCall = std::variant<LoadModelCall, GetFunctionCall, ListFunctionsCall, HealthCall, ReleaseCall,
                               SubmitJobCall, JobStatusCall, CancelJobCall, JobResultCall, QueryArtifactCall,
                               FetchArtifactChunkCall, FleetStatusCall>;

class Connection {
 public:
  virtual ~Connection() = default;

  virtual std::string_view transport() const = 0;  // "iceoryx", "dds"

  // The unary methods (every method but the evaluations) all go through call(): one
  // virtual entry point a transport implements once, whatever the message.
  Status loadModel(const rpc::LoadModelRequest& request, rpc::LoadModelReply& reply, CallOptions options = {}) {
    return call(UnaryCall{LoadModelCall{&request, &reply}}, options);
  }
  Status getFunction(const rpc::GetFunctionRequest& request, rpc::GetFunctionReply& reply, CallOptions options = {}) {
    return call(UnaryCall{GetFunctionCall{&request, &reply}}, options);
  }
  Status listFunctions(const rpc::ListFunctionsRequest& request, rpc::ListFunctionsReply& reply,
                       CallOptions options = {}) {
    return call(UnaryCall{ListFunctionsCall{&request, &reply}}, options);
  }
  Status health(const rpc::HealthRequest& request, rpc::HealthReply& reply, CallOptions options = {}) {
    return call(UnaryCall{HealthCall{&request, &reply}}, options);
  }
  Status release(const rpc::ReleaseRequest& request, rpc::ReleaseReply& reply, CallOptions options = {}) {
    return call(UnaryCall{ReleaseCall{&request, &reply}}, options);
  }
  // Jobs: batch work run by the server in its worker processes.
  Status submitJob(const rpc::SubmitJobRequest& request, rpc::SubmitJobReply& reply, CallOptions options = {}) {
    return call(UnaryCall{SubmitJobCall{&request, &reply}}, options);
  }
  Status jobStatus(const rpc::JobStatusRequest& request, rpc::JobStatusReply& reply, CallOptions options = {}) {
    return call(UnaryCall{JobStatusCall{&request, &reply}}, options);
  }
  Status cancelJob(const rpc::CancelJobRequest& request, rpc::CancelJobReply& reply, CallOptions options = {}) {
    return call(UnaryCall{CancelJobCall{&request, &reply}}, options);
  }
  Status jobResult(const rpc::JobResultRequest& request, rpc::JobResultReply& reply, CallOptions options = {}) {
    return call(UnaryCall{JobResultCall{&request, &reply}}, options);
  }

  // One unary call of any method; the reply is meaningful only when the status is OK.
  virtual Status call(const UnaryCall& unary, CallOptions options) = 0;

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
