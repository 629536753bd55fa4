#pragma once
// The service's messages: the one description of every wire struct. Each struct is followed
// by its field list (field_list.hpp), from which everything else is derived: the IDL structs
// for idlc (written at build time into robodiff.idl by robodiff_idl_writer, idl_writer.hpp),
// the DDS codec (dds_codec.hpp: to and from the idlc-generated C types) and the iceoryx codec
// (shm_codec.hpp: flat shared-memory chunks). The server and the client work only with
// these. Adding a field: the struct and its ROBODIFF_FIELDS line here, nothing else (the
// codecs' tests fill and compare every field through the same lists). A new enum also needs
// its values in schema/robodiff.idl.in and an idlName / valueCount pair below.
//
// Evaluate and EvaluateBatch carry their doubles outside these structs (spans over the
// transport's buffers) so that iceoryx can serve them without copying the payload; see
// server/service_api.hpp and client/connection.hpp.

#include <cstdint>
#include <string>
#include <vector>

#include "robodiff/schema/field_list.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::rpc {

enum class Method : std::uint32_t {  // robodiff_wire_Method
  LoadModel = 0,
  GetFunction = 1,
  Evaluate = 2,
  EvaluateBatch = 3,
  ListFunctions = 4,
  Health = 5,
  Release = 6,
  SubmitJob = 7,
  JobStatus = 8,
  CancelJob = 9,
  JobResult = 10,
  QueryArtifact = 11,
  FetchArtifactChunk = 12,
  FleetStatus = 13,
};
inline constexpr std::uint32_t kMethodCount = 14;
const char* toString(Method method);  // "LoadModel", ...

// valueCount(e): how many values an enum has (the codecs refuse others off the wire);
// idlName(e): the enum's name in robodiff.idl.in (the generated IDL types a field by it).
constexpr std::uint32_t valueCount(Method) { return kMethodCount; }
constexpr std::uint32_t valueCount(StatusCode) { return kStatusCodeCount; }
constexpr const char* idlName(Method) { return "Method"; }
constexpr const char* idlName(StatusCode) { return "StatusCode"; }

ROBODIFF_FIELDS(Status, code, message);

struct SchemaVersion {
  std::uint16_t major = kSchemaVersionMajor;
  std::uint16_t minor = kSchemaVersionMinor;
};
ROBODIFF_FIELDS(SchemaVersion, major, minor);

struct RequestHeader {
  SchemaVersion schema_version;
  std::string client_id;               // unique per client process / instance
  std::uint64_t correlation_id = 0;    // chosen by the client, unique per client
  // Counted from when the server takes the request; 0 = none. Relative (as gRPC's
  // grpc-timeout) so that the hosts' clocks need not agree; the client enforces its own
  // absolute deadline.
  std::uint64_t deadline_budget_ns = 0;
  std::string server_instance_id;      // the server asked; empty = any server
};
ROBODIFF_FIELDS(RequestHeader, schema_version, client_id, correlation_id, deadline_budget_ns, server_instance_id);

struct ReplyHeader {
  SchemaVersion schema_version;        // the server's
  std::string server_instance_id;
  std::string client_id;               // copied from the request
  std::uint64_t correlation_id = 0;    // copied from the request
  Status status;                       // non-OK: the body is still the method's (maybe empty) reply
};
ROBODIFF_FIELDS(ReplyHeader, schema_version, server_instance_id, client_id, correlation_id, status);

// ---- LoadModel ----------------------------------------------------------------------

struct LoadModelRequest {
  std::string urdf;                    // URDF text
  bool floating_base = false;          // add a free-flyer root joint
  std::string options_json;            // further options, a JSON object; empty = defaults
};
ROBODIFF_FIELDS(LoadModelRequest, urdf, floating_base, options_json);

struct LoadModelReply {
  std::string model_id;                // canonical hash (hex)
  std::vector<std::string> joint_names;
  std::vector<std::string> frame_names;
  std::uint32_t nq = 0, nv = 0;
};
ROBODIFF_FIELDS(LoadModelReply, model_id, joint_names, frame_names, nq, nv);

// ---- GetFunction --------------------------------------------------------------------

enum class FunctionState : std::uint32_t { Ready = 0, Building = 1, Failed = 2 };
enum class OutputKind : std::uint32_t { Value = 0, Jacobian = 1, Hessian = 2 };
enum class OutputLayout : std::uint32_t { DenseRowMajor = 0, SparseCsr = 1 };
const char* toString(FunctionState state);  // "READY", "BUILDING", "FAILED"
constexpr std::uint32_t valueCount(FunctionState) { return 3; }
constexpr std::uint32_t valueCount(OutputKind) { return 3; }
constexpr std::uint32_t valueCount(OutputLayout) { return 2; }
constexpr const char* idlName(FunctionState) { return "FunctionState"; }
constexpr const char* idlName(OutputKind) { return "OutputKind"; }
constexpr const char* idlName(OutputLayout) { return "OutputLayout"; }

struct InputBlock {
  std::string name;                    // q, v, a, tau, weights, ...
  std::uint32_t size = 0;              // doubles
};
ROBODIFF_FIELDS(InputBlock, name, size);

struct OutputBlock {
  std::string name;                    // value, jacobian, hessian, ...
  OutputKind kind = OutputKind::Value;
  std::uint32_t rows = 0, cols = 0;
  OutputLayout layout = OutputLayout::DenseRowMajor;
  std::uint32_t nnz = 0;               // doubles written (rows * cols when dense)
  std::vector<std::uint32_t> row_offsets;  // sparse: rows + 1
  std::vector<std::uint32_t> col_indices;  // sparse: nnz
};
ROBODIFF_FIELDS(OutputBlock, name, kind, rows, cols, layout, nnz, row_offsets, col_indices);

struct GetFunctionRequest {
  std::string model_id;
  std::string spec_json;               // a function spec (schema/function-spec.schema.json)
  bool wait = false;                   // reply when READY / FAILED (or at the deadline)
};
ROBODIFF_FIELDS(GetFunctionRequest, model_id, spec_json, wait);

struct GetFunctionReply {
  std::string function_id;
  FunctionState state = FunctionState::Building;
  std::vector<InputBlock> inputs;      // in evaluation order
  std::vector<OutputBlock> outputs;    // in evaluation order
};
ROBODIFF_FIELDS(GetFunctionReply, function_id, state, inputs, outputs);

// Doubles per knot in and out, as the blocks above add up.
std::uint32_t inputCount(const GetFunctionReply& function);
std::uint32_t outputCount(const GetFunctionReply& function);

// ---- Evaluate / EvaluateBatch (headers only: the doubles travel beside them) ---------

struct EvaluateRequest {
  std::string function_id;
  std::vector<double> inputs;          // used where a transport copies (DDS); every block, in order
};
ROBODIFF_FIELDS(EvaluateRequest, function_id, inputs);

struct EvaluateReply {
  std::vector<double> outputs;         // every output block, in order
};
ROBODIFF_FIELDS(EvaluateReply, outputs);

struct EvaluateBatchRequest {
  std::string function_id;
  std::uint32_t knot_count = 0;
  std::vector<double> inputs;          // knot_count knots, each the concatenated blocks
};
ROBODIFF_FIELDS(EvaluateBatchRequest, function_id, knot_count, inputs);

// A batch reply may be split into chunk_count replies at knot boundaries, each with the
// request's correlation id; chunk i holds knots [first_knot, first_knot + knot_count). A
// non-OK status ends the reply at once.
struct EvaluateBatchReply {
  std::uint32_t chunk_index = 0, chunk_count = 1;  // 0 .. chunk_count - 1; chunk_count >= 1
  std::uint32_t total_knots = 0, first_knot = 0, knot_count = 0;  // total: the request's knots
  std::vector<double> outputs;         // knot_count knots, each the concatenated output blocks
};
ROBODIFF_FIELDS(EvaluateBatchReply, chunk_index, chunk_count, total_knots, first_knot, knot_count, outputs);

// ---- ListFunctions ------------------------------------------------------------------

// Paged: a reply holds at most page_size functions (the server caps it at
// kMaxListFunctionsPage, and at a byte budget so that a reply fits one shm chunk or DDS
// sample); next_page_token asks for the next page (client::listAllFunctions follows it).
inline constexpr std::uint32_t kMaxListFunctionsPage = 200;

struct ListFunctionsRequest {
  std::string model_id;                // empty = all
  std::uint32_t page_size = 0;         // 0: kMaxListFunctionsPage
  std::string page_token;              // empty: the first page; else an earlier reply's next_page_token
};
ROBODIFF_FIELDS(ListFunctionsRequest, model_id, page_size, page_token);

struct FunctionSummary {
  std::string function_id;
  std::string model_id;
  std::string function_name;           // rnea, aba, ...
  FunctionState state = FunctionState::Building;
  bool compiled = false;               // false while the interpreter serves it
  std::uint64_t evaluations = 0;       // knots evaluated
  std::string message;                 // FAILED: why
};
ROBODIFF_FIELDS(FunctionSummary, function_id, model_id, function_name, state, compiled, evaluations, message);

struct ListFunctionsReply {
  std::vector<FunctionSummary> functions;  // in order of creation
  std::string next_page_token;         // empty: this was the last page
  std::uint32_t total = 0;             // functions listed over all pages (when this page was made)
};
ROBODIFF_FIELDS(ListFunctionsReply, functions, next_page_token, total);

// ---- Release ------------------------------------------------------------------------

// Each LoadModel / GetFunction that returns an id takes a reference; Release gives one
// back. A function keeps its model alive (after the model's last reference is gone); an
// unreferenced function is unloaded.
struct ReleaseRequest {
  std::string id;                      // a model_id or a function_id
};
ROBODIFF_FIELDS(ReleaseRequest, id);

struct ReleaseReply {
  std::uint32_t references_left = 0;   // 0: unloaded
};
ROBODIFF_FIELDS(ReleaseReply, references_left);

// ---- Jobs ---------------------------------------------------------------------------

// Batch work in worker processes: a function along a trajectory, identifying inertial
// parameters, optimising a trajectory. Parameters and result summary are JSON (the kinds
// and their fields: docs/jobs.md); result files are written on the server's host.
enum class JobState : std::uint32_t { Queued = 0, Running = 1, Succeeded = 2, Failed = 3, Cancelled = 4 };
const char* toString(JobState state);  // "QUEUED", "RUNNING", "SUCCEEDED", "FAILED", "CANCELLED"
constexpr std::uint32_t valueCount(JobState) { return 5; }
constexpr const char* idlName(JobState) { return "JobState"; }
inline bool isFinal(JobState s) { return s != JobState::Queued && s != JobState::Running; }

struct SubmitJobRequest {
  std::string kind;                    // "trajectory", "identify", "trajopt"
  std::string params_json;             // a JSON object
};
ROBODIFF_FIELDS(SubmitJobRequest, kind, params_json);

struct SubmitJobReply {
  std::string job_id;
};
ROBODIFF_FIELDS(SubmitJobReply, job_id);

struct JobInfo {
  std::string job_id;
  std::string kind;
  JobState state = JobState::Queued;
  double progress = 0;                 // 0 .. 1
  double elapsed_seconds = 0;          // since it started running (0 while queued)
  double eta_seconds = -1;             // remaining, from the progress; < 0: unknown
  std::vector<std::string> messages;   // what the job said: the latest few, oldest first
  std::string error;                   // FAILED / CANCELLED: why
};
ROBODIFF_FIELDS(JobInfo, job_id, kind, state, progress, elapsed_seconds, eta_seconds, messages, error);

struct JobStatusRequest {
  std::string job_id;                  // empty = every job
};
ROBODIFF_FIELDS(JobStatusRequest, job_id);

struct JobStatusReply {
  std::vector<JobInfo> jobs;
};
ROBODIFF_FIELDS(JobStatusReply, jobs);

struct CancelJobRequest {
  std::string job_id;
};
ROBODIFF_FIELDS(CancelJobRequest, job_id);

struct CancelJobReply {
  JobState state = JobState::Cancelled;  // after the cancel (a finished job keeps its state)
};
ROBODIFF_FIELDS(CancelJobReply, state);

struct JobResultRequest {
  std::string job_id;
};
ROBODIFF_FIELDS(JobResultRequest, job_id);

// FAILED_PRECONDITION while the job has not succeeded.
struct JobResultReply {
  JobInfo info;
  std::string result_json;             // the job's result summary
  std::string result_dir;              // its files, on the server's host
};
ROBODIFF_FIELDS(JobResultReply, info, result_json, result_dir);

// ---- Artifacts (a fleet: robot hosts fetch signed libraries from build hosts) --------

// A robot host asks a build host for a function's library by its portable key (docs/fleet.md),
// then pulls the signed entry's files in chunks. Only a server configured as a build host
// answers (FAILED_PRECONDITION otherwise).
enum class ArtifactState : std::uint32_t { Have = 0, Building = 1, Lack = 2, Failed = 3 };
const char* toString(ArtifactState state);  // "HAVE", "BUILDING", "LACK", "FAILED"
constexpr std::uint32_t valueCount(ArtifactState) { return 4; }
constexpr const char* idlName(ArtifactState) { return "ArtifactState"; }

struct QueryArtifactRequest {
  std::string portable_key;            // cache::preparePortableKey on the robot (no compiler needed)
  std::string urdf;                    // the robot's URDF text: the build host checks and builds from it
  bool floating_base = false;
  std::string spec_json;               // the normalised spec, build.target naming the robot's x86-64 level
  bool build = false;                  // true: a library the build host lacks is built (BUILDING), not LACK
  bool include_sources = false;        // the generated C travels too (larger)
};
ROBODIFF_FIELDS(QueryArtifactRequest, portable_key, urdf, floating_base, spec_json, build, include_sources);

struct QueryArtifactReply {
  ArtifactState state = ArtifactState::Lack;
  std::string key;                     // HAVE: the entry's key (the build host's compiler in it)
  std::string manifest_json;           // HAVE: the signed manifest (cache/entry_manifest.hpp)
  std::string signature_hex;           // HAVE: its Ed25519 signature
  std::uint64_t payload_bytes = 0;     // HAVE: the manifest's files, concatenated in its order
  std::uint32_t builds_queued = 0;     // BUILDING: builds ahead of and including this one
  std::string message;                 // LACK / FAILED: why
};
ROBODIFF_FIELDS(QueryArtifactReply, state, key, manifest_json, signature_hex, payload_bytes, builds_queued, message);

struct FetchArtifactChunkRequest {
  std::string key;                     // a key a QueryArtifact answered HAVE with
  bool include_sources = false;        // as in that query
  std::uint64_t offset = 0;            // into the payload
  std::uint32_t max_bytes = 0;         // 0: the server's chunk size; capped by it
};
ROBODIFF_FIELDS(FetchArtifactChunkRequest, key, include_sources, offset, max_bytes);

struct FetchArtifactChunkReply {
  std::uint64_t offset = 0;            // the request's
  std::uint64_t payload_bytes = 0;     // the whole payload
  std::vector<std::uint8_t> data;      // payload bytes from offset; empty at the end
};
ROBODIFF_FIELDS(FetchArtifactChunkReply, offset, payload_bytes, data);

// ---- Health -------------------------------------------------------------------------

enum class ServingState : std::uint32_t { Starting = 0, Serving = 1, Draining = 2 };
const char* toString(ServingState state);  // "STARTING", "SERVING", "DRAINING"
constexpr std::uint32_t valueCount(ServingState) { return 3; }
constexpr const char* idlName(ServingState) { return "ServingState"; }

struct HealthRequest {
  bool verbose = false;                // reserved for per-method detail (a body may not be empty)
};
ROBODIFF_FIELDS(HealthRequest, verbose);

struct MethodStats {
  Method method = Method::Health;
  std::uint64_t requests = 0;
  std::uint64_t errors = 0;            // non-OK replies
  std::uint64_t p50_ns = 0, p90_ns = 0, p99_ns = 0, max_ns = 0;  // server-side latency
};
ROBODIFF_FIELDS(MethodStats, method, requests, errors, p50_ns, p90_ns, p99_ns, max_ns);

struct StatusCount {
  StatusCode code = StatusCode::Ok;
  std::uint64_t count = 0;
};
ROBODIFF_FIELDS(StatusCount, code, count);

struct TransportCounts {
  std::string transport;               // "iceoryx", "dds"
  std::uint64_t requests = 0;
  std::uint64_t errors = 0;
};
ROBODIFF_FIELDS(TransportCounts, transport, requests, errors);

// A build host a robot host asks for artifacts, as the robot sees it.
struct FleetPeer {
  std::string service;                 // its DDS service name (fleet.build_hosts)
  std::string instance_id;             // the server that last answered; empty: never reached
  bool reachable = false;              // its last call got an answer
  std::uint64_t artifacts_fetched = 0, bytes_fetched = 0, refusals = 0, failures = 0;
  double fetch_seconds = 0;            // the fetched ones' transfer, verification and filing, added up
  std::string last_problem;            // the latest refusal or failure
};
ROBODIFF_FIELDS(FleetPeer, service, instance_id, reachable, artifacts_fetched, bytes_fetched, refusals, failures,
                fetch_seconds, last_problem);

// This server's part in a fleet (docs/fleet.md).
struct FleetFigures {
  std::string role;                    // "standalone", "build", "robot"
  std::string target;                  // robot: the x86-64 level it asks builds for
  std::uint64_t artifacts_fetched = 0, bytes_fetched = 0;   // robot: verified and filed
  std::uint64_t artifacts_refused = 0;                      // robot: failed verification
  std::uint64_t fetch_failures = 0;                         // robot: no build host could deliver
  std::uint64_t artifacts_served = 0, bytes_served = 0;     // build host: whole payloads, chunk bytes
  std::uint64_t builds_for_robots = 0;                      // build host: builds robots asked for
  std::vector<FleetPeer> peers;        // robot: its build hosts
};
ROBODIFF_FIELDS(FleetFigures, role, target, artifacts_fetched, bytes_fetched, artifacts_refused, fetch_failures,
                artifacts_served, bytes_served, builds_for_robots, peers);

// `robodiff health` asks it beside Health (a 2.0 server answers UNIMPLEMENTED).
struct FleetStatusRequest {
  bool verbose = false;                // reserved (a body may not be empty)
};
ROBODIFF_FIELDS(FleetStatusRequest, verbose);

struct FleetStatusReply {
  FleetFigures fleet;
};
ROBODIFF_FIELDS(FleetStatusReply, fleet);

struct HealthReply {
  ServingState state = ServingState::Starting;
  std::string version;                 // robodiff's
  std::string server_instance_id;
  std::uint64_t uptime_ns = 0;
  std::uint32_t models_loaded = 0;
  std::uint32_t functions_loaded = 0;
  std::uint32_t functions_compiled = 0;  // the rest are served by the interpreter
  std::uint32_t builds_queued = 0, builds_running = 0, builds_failed = 0, builds_done = 0;
  std::uint64_t cache_hits = 0, cache_misses = 0;
  std::uint64_t cache_bytes = 0, cache_entries = 0;
  std::uint32_t workers_total = 0, workers_busy = 0;
  std::uint32_t queue_depth = 0, queue_capacity = 0;       // requests waiting for a server thread
  std::uint32_t batch_threads = 0;
  std::vector<MethodStats> methods;    // one per method, in Method order
  std::vector<StatusCount> errors;     // non-OK codes seen, with counts
  std::vector<TransportCounts> transports;
};
ROBODIFF_FIELDS(HealthReply, state, version, server_instance_id, uptime_ns, models_loaded, functions_loaded,
                functions_compiled, builds_queued, builds_running, builds_failed, builds_done, cache_hits,
                cache_misses, cache_bytes, cache_entries, workers_total, workers_busy, queue_depth,
                queue_capacity, batch_threads, methods, errors, transports);

// Every request and reply, X(Name) each, in Method order (request, then reply): the codecs
// instantiate themselves and the tests cover every message from this list.
#define ROBODIFF_RPC_MESSAGES(X)                                        \
  X(LoadModelRequest) X(LoadModelReply) X(GetFunctionRequest) X(GetFunctionReply)       \
  X(EvaluateRequest) X(EvaluateReply) X(EvaluateBatchRequest) X(EvaluateBatchReply)     \
  X(ListFunctionsRequest) X(ListFunctionsReply) X(HealthRequest) X(HealthReply)         \
  X(ReleaseRequest) X(ReleaseReply) X(SubmitJobRequest) X(SubmitJobReply)               \
  X(JobStatusRequest) X(JobStatusReply) X(CancelJobRequest) X(CancelJobReply)           \
  X(JobResultRequest) X(JobResultReply) X(QueryArtifactRequest) X(QueryArtifactReply)                   \
  X(FetchArtifactChunkRequest) X(FetchArtifactChunkReply) X(FleetStatusRequest) X(FleetStatusReply)

}  // namespace robodiff::rpc
