#pragma once
// The controller-facing client: connect to robodiff, load a model, get Function handles
// from specs, evaluate them with Eigen types or spans over the caller's memory.
//
// Three ways to evaluate behind one API:
//   Local - the compiled library is loaded from the shared cache into this process and
//           called directly (the fastest; same host; needs the library in the cache:
//           a server or `robodiff warmup` built it). Keeps working when the server goes.
//   Shm   - iceoryx request/response to robodiffd on this host.
//   Dds   - Cyclone DDS to robodiffd anywhere in the domain.
// Mode::Auto picks Local when the cache is reachable, then Shm, then Dds.
//
// Local and Auto (with the cache reachable): models and functions are still loaded
// through the server when one answers (so that it builds and caches them); a Function
// evaluates in-process once its library is in the cache (SHA-256 verified by the cache,
// pinned while loaded) and through the server until then (the cache is looked at again
// from calling threads at most every 100 ms). A library that fails verification is never
// used: Auto evaluates through the server, insisted Local refuses (FAILED_PRECONDITION).
// Without a server, Local parses the URDF and computes the cache key itself; a function
// not in the cache is FAILED_PRECONDITION (run `robodiff warmup` or start robodiffd).
//
// Threads: a Client and its Functions may be shared by many threads. Local evaluation never
// allocates after a thread's first call on a Function (the work buffer is per thread),
// and takes no lock in Local mode. Errors are statuses (StatusCode + message), never a
// silent wrong value; the throwing calls throw ClientError carrying the status.
//
// Server restarts: Shm and Dds calls report UNAVAILABLE while no server answers; the
// client registers its models and functions again on the next server (ids are content
// hashes, so Function handles stay valid).

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <future>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "robodiff/client/connection.hpp"
#include "robodiff/schema/messages.hpp"

namespace robodiff::client {

enum class Mode { Auto, Local, Shm, Dds };
const char* toString(Mode mode);  // "auto", "local", "shm", "dds"

// Where the server is: "auto", "local", "shm", "shm:<service>", "dds", "dds:<domain>".
struct ServerAddress {
  Mode mode = Mode::Auto;
  std::string shm_service = "robodiff";
  std::int32_t dds_domain = -1;  // -1: Cyclone's default (CYCLONEDDS_URI)
};
// Throws std::invalid_argument naming the text and the accepted forms.
ServerAddress parseServerAddress(std::string_view text);
// $ROBODIFF_SERVER when set, else "auto".
ServerAddress serverAddressFromEnvironment();

struct ClientOptions {
  ServerAddress server = serverAddressFromEnvironment();
  std::filesystem::path cache_dir;  // Local mode; empty: the default cache (cache::defaultCacheDir)
  std::chrono::nanoseconds timeout = std::chrono::seconds(30);  // per call unless CallOptions says
  std::string client_id;            // empty: defaultClientId()
  std::size_t async_threads = 2;    // Function::evaluateAsync's threads
  std::size_t async_queue = 64;     // evaluateAsync calls queued or running at most
};

class ClientError : public std::runtime_error {
 public:
  explicit ClientError(Status status) : std::runtime_error(toString(status.code) + ": " + status.message),
                                        status_(std::move(status)) {}
  const Status& status() const { return status_; }

 private:
  Status status_;
};

struct ModelInfo {
  std::string id;  // canonical hash
  std::vector<std::string> joint_names, frame_names;
  int nq = 0, nv = 0;
};

// A function's outputs for one knot, as Eigen matrices (dense; sparse blocks expanded).
struct Outputs {
  std::vector<Eigen::MatrixXd> blocks;  // one per output block, rows x cols
  const Eigen::MatrixXd& operator[](std::size_t i) const { return blocks.at(i); }
};

class Function {
 public:
  Function() = default;  // empty; valid() is false
  bool valid() const { return impl_ != nullptr; }

  const std::string& id() const;
  const rpc::GetFunctionReply& layout() const;  // input and output blocks, CSR patterns
  std::size_t inputCount() const;               // doubles per knot, all input blocks
  std::size_t outputCount() const;
  Mode mode() const;                            // how this handle evaluates now

  // The hot path. `inputs`: the input blocks concatenated (q, v, a, ...); `outputs`: room
  // for the output blocks concatenated (sparse blocks: their nnz values in CSR order).
  Status evaluate(std::span<const double> inputs, std::span<double> outputs) const;
  Status evaluate(std::span<const double> inputs, std::span<double> outputs, std::chrono::nanoseconds timeout) const;
  // knots one after another, in and out. Local: the library's batched entry point (its
  // batch width of knots in SIMD lanes), results within 1e-12 relative of single calls
  // and bit-identical to the server's EvaluateBatch on the same library.
  Status evaluateBatch(std::size_t knots, std::span<const double> inputs, std::span<double> outputs,
                       std::chrono::nanoseconds timeout = std::chrono::nanoseconds(0)) const;
  // knots with each block in its own memory, knot after knot (input block b of knot k at
  // inputs[b] + k * size_b; outputs alike): one array per block, as numpy holds them.
  // Local: handed to the library as they are (its own batched layout), nothing copied;
  // a server: packed knot after knot and sent as evaluate/evaluateBatch would. batch
  // false evaluates one knot (evaluate's path), true `knots` (evaluateBatch's). The
  // caller guarantees the block counts and sizes.
  Status evaluateBlocks(std::size_t knots, std::span<const double* const> inputs, std::span<double* const> outputs,
                        bool batch) const;
  // The same, returning at once; the spans must stay valid until the future is ready.
  // Runs on the Client's async threads (ClientOptions::async_threads, started by the
  // first call); allocates nothing after that thread's first call on this Function. More
  // than ClientOptions::async_queue calls pending: the future holds RESOURCE_EXHAUSTED.
  std::future<Status> evaluateAsync(std::span<const double> inputs, std::span<double> outputs) const;

  // One output block of `outputs` (a knot's concatenated outputs, as evaluate wrote them)
  // as an Eigen view, no copy: the values stay in `outputs`. sparseBlock gives a CSR
  // block as a row-major sparse matrix (its pattern is the function's, fixed); denseBlock
  // a dense one, row-major. Throw ClientError (INVALID_ARGUMENT) for a block of the other
  // layout, a block index out of range, or outputs too short.
  using SparseBlock = Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>>;
  using DenseBlock = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
  SparseBlock sparseBlock(std::size_t block, std::span<const double> outputs) const;
  DenseBlock denseBlock(std::size_t block, std::span<const double> outputs) const;

  // Convenience (allocates): one Eigen vector per input block in, dense matrices out.
  // Throws ClientError.
  Outputs operator()(const std::vector<Eigen::VectorXd>& inputs) const;

  struct Impl;
  explicit Function(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

 private:
  std::shared_ptr<Impl> impl_;
};

class Client {
 public:
  // Connects per options.server. Auto never fails here (it may end up with Local only
  // and no server); an insisted mode that cannot be reached throws ClientError
  // (UNAVAILABLE, saying what was tried).
  explicit Client(ClientOptions options = {});
  ~Client();
  Client(Client&&) noexcept;
  Client& operator=(Client&&) noexcept;

  Mode mode() const;  // the mode in use: Local, Shm or Dds

  // Throw ClientError (INVALID_ARGUMENT with the URDF's problem, UNAVAILABLE, ...).
  ModelInfo loadModel(const std::string& urdf_text, bool floating_base = false);
  ModelInfo loadModelFile(const std::filesystem::path& urdf_path, bool floating_base = false);
  // Waits until the function can be evaluated (compiled, or interpreted by the server).
  Function function(const ModelInfo& model, const std::string& spec_json);
  // The same from a spec file (a built-in function's or a user function's JSON).
  Function functionFile(const ModelInfo& model, const std::filesystem::path& spec_path);

  rpc::HealthReply health();                      // from the server; throws without one
  // The server's part in a fleet (role, peers, artifact counts; docs/fleet.md). Throws
  // without a server, and with the server's status (UNIMPLEMENTED from a 2.0 server).
  rpc::FleetStatusReply fleetStatus();
  std::vector<rpc::FunctionSummary> functions();  // ListFunctions

  // Batch jobs, run by the server in its worker processes (client/api/src/jobs.cpp; the
  // kinds and their parameters: schema/README.md). Need a server; throw ClientError
  // (INVALID_ARGUMENT for bad parameters, NOT_FOUND for an unknown job, UNAVAILABLE).
  std::string submitJob(const std::string& kind, const std::string& params_json);  // the job's id
  std::vector<rpc::JobInfo> jobs();                      // every job the server knows
  rpc::JobInfo jobStatus(const std::string& job_id);
  rpc::JobState cancelJob(const std::string& job_id);    // the state after the cancel
  rpc::JobResultReply jobResult(const std::string& job_id);  // a finished job's summary and files

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace robodiff::client
