#pragma once
// What a transport (server/dds, server/shm) calls: the service's methods on the C++
// messages of robodiff/schema/messages.hpp, independent of how requests arrive.
// server::Service (service.hpp) implements it; transport tests may use small fakes.
//
// Threading: every method may be called from any thread at once. Evaluate is cheap
// (microseconds) and transports call it on their receiving thread; the other methods may
// take long (tracing a humanoid, waiting for a build) and transports hand them to
// post(), which runs them on the service's request threads, or refuses when its bounded
// queue is full (the transport then replies RESOURCE_EXHAUSTED).
//
// Zero copy: Evaluate / EvaluateBatch read inputs from and write outputs into memory the
// transport owns (shared-memory chunks for iceoryx). A transport first asks shape() for
// the sizes, sizes and allocates (loans) the reply, then calls evaluate*().

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>

#include "robodiff/schema/messages.hpp"

namespace robodiff::server {

using Clock = std::chrono::steady_clock;

// Who is calling, as the transport established it (deploy/security.md, "Ownership"). Models,
// functions and jobs belong to the caller that made them; only an operator acts on others'.
//   "dds:alice"  a DDS Security identity (authenticated: its certificate and signed permissions)
//   "user:alice" an OS user: over iceoryx from the client process's uid, over open DDS as the
//                client claims it (advisory only)
//   "local"      the process itself (in-process use, tests): owner of what it made
struct Caller {
  std::string name = "local";
  bool operator_ = false;      // may see and act on every caller's jobs, functions and models
  bool authenticated = false;  // proven by DDS Security, not claimed or inferred

  bool mayActOn(std::string_view owner) const { return operator_ || owner == name; }
};

// Who asked, and until when the answer is useful.
struct CallContext {
  std::string_view transport;          // "iceoryx", "dds", "inproc"
  std::string_view client_id;
  std::uint64_t correlation_id = 0;
  Caller caller;                       // set by the transport for the methods that need it
  Clock::time_point received = Clock::now();
  Clock::time_point deadline = Clock::time_point::max();  // received + the request's budget

  bool expired(Clock::time_point now = Clock::now()) const { return now >= deadline; }
  // From a request header: deadline = received + deadline_budget_ns (0: none).
  static CallContext from(const rpc::RequestHeader& header, std::string_view transport,
                          Clock::time_point received = Clock::now()) {
    CallContext ctx;
    ctx.transport = transport;
    ctx.client_id = header.client_id;
    ctx.correlation_id = header.correlation_id;
    ctx.received = received;
    if (header.deadline_budget_ns != 0) {
      const auto budget = std::chrono::nanoseconds(
          std::min<std::uint64_t>(header.deadline_budget_ns, std::uint64_t{1} << 62));
      ctx.deadline = received + std::chrono::duration_cast<Clock::duration>(budget);
    }
    return ctx;
  }
};

// Sizes of a loaded function, per knot.
struct FunctionShape {
  std::uint32_t input_count = 0;       // doubles in: the concatenated input blocks
  std::uint32_t output_count = 0;      // doubles out: the concatenated output blocks
  std::uint32_t max_batch_knots = 0;   // the most knots one EvaluateBatch may carry
};

class ServiceApi {
 public:
  virtual ~ServiceApi() = default;

  // The server's instance id (unique per process start), put in every reply header.
  virtual const std::string& instanceId() const = 0;

  // Checks a request header before anything else: schema version (FAILED_PRECONDITION),
  // a server_instance_id naming another server (NOT_FOUND... transports drop those
  // silently instead, since another server will answer), draining (UNAVAILABLE).
  virtual Status admit(const rpc::RequestHeader& header) const = 0;

  virtual Status loadModel(const CallContext& ctx, const rpc::LoadModelRequest& request,
                           rpc::LoadModelReply& reply) = 0;
  virtual Status getFunction(const CallContext& ctx, const rpc::GetFunctionRequest& request,
                             rpc::GetFunctionReply& reply) = 0;
  virtual Status listFunctions(const CallContext& ctx, const rpc::ListFunctionsRequest& request,
                               rpc::ListFunctionsReply& reply) = 0;
  virtual Status health(const CallContext& ctx, const rpc::HealthRequest& request, rpc::HealthReply& reply) = 0;
  // NOT_FOUND for an id that is not loaded (or has no references left).
  virtual Status release(const CallContext& ctx, const rpc::ReleaseRequest& request, rpc::ReleaseReply& reply) = 0;

  // Jobs: batch work in worker processes (schema/README.md). The defaults answer
  // UNIMPLEMENTED, for a service without a job runner (transport tests' fakes).
  virtual Status submitJob(const CallContext& ctx, const rpc::SubmitJobRequest& request, rpc::SubmitJobReply& reply) {
    return noJobs();
  }
  virtual Status jobStatus(const CallContext& ctx, const rpc::JobStatusRequest& request, rpc::JobStatusReply& reply) {
    return noJobs();
  }
  virtual Status cancelJob(const CallContext& ctx, const rpc::CancelJobRequest& request, rpc::CancelJobReply& reply) {
    return noJobs();
  }
  virtual Status jobResult(const CallContext& ctx, const rpc::JobResultRequest& request, rpc::JobResultReply& reply) {
    return noJobs();
  }
  static Status noJobs() { return {StatusCode::Unimplemented, "this server runs no jobs"}; }

  // A fleet (docs/fleet.md): robot hosts fetch signed libraries from build hosts. The
  // defaults are a server that is no build host (the artifact methods answer
  // FAILED_PRECONDITION) and stands alone (FleetStatus: role "standalone").
  virtual Status queryArtifact(const CallContext& ctx, const rpc::QueryArtifactRequest& request,
                               rpc::QueryArtifactReply& reply) {
    return notABuildHost();
  }
  virtual Status fetchArtifactChunk(const CallContext& ctx, const rpc::FetchArtifactChunkRequest& request,
                                    rpc::FetchArtifactChunkReply& reply) {
    return notABuildHost();
  }
  virtual Status fleetStatus(const CallContext& ctx, const rpc::FleetStatusRequest& request,
                             rpc::FleetStatusReply& reply) {
    reply.fleet.role = "standalone";
    return {};
  }
  static Status notABuildHost() {
    return {StatusCode::FailedPrecondition,
            "this server is not a build host (fleet.role = build serves artifacts; docs/fleet.md)"};
  }

  // NOT_FOUND for an unknown (or released) function id; otherwise its sizes.
  virtual Status shape(std::string_view function_id, FunctionShape& shape) = 0;
  // One knot: inputs.size() must be input_count and outputs.size() output_count
  // (INVALID_ARGUMENT naming both otherwise); a NaN or infinite input is INVALID_ARGUMENT
  // naming its block and index. Outputs are untouched unless the status is OK.
  virtual Status evaluate(const CallContext& ctx, std::string_view function_id, std::span<const double> inputs,
                          std::span<double> outputs) = 0;
  // `knots` knots, each input_count doubles in and output_count out, knot after knot.
  // More than max_batch_knots is RESOURCE_EXHAUSTED; spread over the batch threads; the
  // deadline is checked between pieces (DEADLINE_EXCEEDED).
  virtual Status evaluateBatch(const CallContext& ctx, std::string_view function_id, std::uint64_t knots,
                               std::span<const double> inputs, std::span<double> outputs) = 0;

  // Runs `task` on a request thread; false when the bounded queue is full (or the service
  // is stopping), and then the task is not run.
  virtual bool post(std::function<void()> task) = 0;

  // Accounting, called by the transport once the reply is sent (or could not be):
  // per-method counts and latency percentiles, errors by status, per-transport counts.
  virtual void recordRequest(std::string_view transport, rpc::Method method, StatusCode code,
                             std::chrono::nanoseconds latency) = 0;
};

}  // namespace robodiff::server
