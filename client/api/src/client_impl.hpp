#pragma once
// Client::Impl and Function::Impl: what a Client shares with its Functions (the
// connection, the local cache, the registry of models and functions to register again
// on a restarted server).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "robodiff/runtime/function_layout.hpp"
#include "async_executor.hpp"
#include "local_evaluator.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/client/client.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::client {

class ShmConnection;
class DdsConnection;

struct Client::Impl {
  ClientOptions options;
  Mode requested = Mode::Auto;
  Mode remote = Mode::Auto;  // Shm or Dds when there is a connection; Auto: none
  std::unique_ptr<Connection> connection;
  ShmConnection* shm = nullptr;  // the connection, typed (one of them or neither)
  DdsConnection* dds = nullptr;
  std::string tried;             // what connecting tried, for messages

  // Local evaluation: the shared cache (Cache is not thread-safe: cache_mutex).
  std::optional<cache::Cache> cache;
  std::mutex cache_mutex;
  bool localCapable() const { return cache.has_value(); }

  // What this client loaded, to register again on a new server.
  struct ModelRecord {
    ModelInfo info;
    std::string urdf;
    bool floating_base = false;
    std::shared_ptr<const Model> model;  // parsed here when Local evaluation needs it
  };
  struct FunctionRecord {
    std::string model_id, spec_json;
  };
  std::mutex registry_mutex;
  std::map<std::string, ModelRecord> models;
  std::map<std::string, FunctionRecord> functions;  // by function id

  std::mutex reregister_mutex;
  std::atomic<std::uint64_t> generation{0};  // completed re-registrations

  Mode mode() const { return localCapable() ? Mode::Local : remote; }
  // A server answers now (cheap: the transport's own view).
  bool serverPresent() const;
  CallOptions callOptions(std::chrono::nanoseconds timeout = std::chrono::nanoseconds(0)) const {
    return CallOptions{timeout.count() > 0 ? timeout : options.timeout};
  }
  Status noServer() const;

  // The model parsed here (from the URDF this client loaded); throws ClientError.
  std::shared_ptr<const Model> localModel(const std::string& model_id);
  bool knowsModel(const std::string& model_id);
  bool knowsFunction(const std::string& function_id);
  // LoadModel + GetFunction(wait) for every model and function of this client, unless
  // another thread did so since `seen_generation`.
  Status reregister(std::uint64_t seen_generation);

  // evaluateAsync's threads, started by the first asynchronous call.
  std::once_flag async_once;
  std::unique_ptr<detail::AsyncExecutor> async;
  detail::AsyncExecutor& asyncExecutor() {
    std::call_once(async_once, [&] {
      async = std::make_unique<detail::AsyncExecutor>(options.async_threads, options.async_queue);
    });
    return *async;
  }
  // The server's summary of a function (ListFunctions), if it answers.
  std::optional<rpc::FunctionSummary> summary(const std::string& function_id);
};

// Connects per options (connect.cpp). Throws ClientError.
std::shared_ptr<Client::Impl> connectClient(ClientOptions options);

struct Function::Impl {
  std::shared_ptr<Client::Impl> client;
  std::string id, model_id, spec_json;
  rpc::GetFunctionReply layout;
  runtime::FunctionLayout blocks;  // the layout's blocks with their offsets (sizes, checks)
  // Each output block's CSR pattern in Eigen's index type (empty for dense blocks).
  std::vector<std::vector<int>> csr_rows, csr_cols;
  FunctionSpec spec;

  // Local evaluation: set once (then never changed) when the library is loaded.
  std::atomic<const detail::LocalEvaluator*> local{nullptr};
  std::unique_ptr<detail::LocalEvaluator> local_owner;
  // Not local yet but may become so: the cache is looked at again at most every 100 ms.
  bool local_candidate = false;
  std::string key;  // the cache key (empty: unknown, e.g. no compiler here)
  // The portable keys (cache::portableKeysFor), tried in order: find a library built
  // elsewhere (imported or fetched, perhaps for an x86-64 level), with another compiler or
  // none here. Both empty: never local.
  std::vector<std::string> portable_keys;
  std::atomic<std::int64_t> next_check_ns{0};
  std::mutex switch_mutex;

  Mode mode() const {
    return local.load(std::memory_order_acquire) != nullptr ? Mode::Local : client->remote;
  }
  // Looks in the cache once; true when now local. Callers hold switch_mutex.
  bool tryLoadLocal(std::string* problem = nullptr);
  // From the calling thread, never blocking: at most every 100 ms, and only one thread.
  void maybeSwitchToLocal();

  Status evaluateLocal(const detail::LocalEvaluator& local, std::uint64_t knots, std::span<const double> inputs,
                       std::span<double> outputs, bool batch) const;
  Status evaluateRemote(std::uint64_t knots, std::span<const double> inputs, std::span<double> outputs, bool batch,
                        std::chrono::nanoseconds timeout);
};

}  // namespace robodiff::client
