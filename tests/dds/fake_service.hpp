#pragma once
// A small ServiceApi for the DDS transport tests (the real Service is tested end to end
// elsewhere). One function, "fn-double": 3 doubles in, 3 out, outputs = 2 * inputs. Slow
// methods on request: LoadModel with urdf "sleep:<ms>" sleeps that long. post() runs tasks on
// `threads` threads with a queue of at most `queue_capacity` waiting tasks. Every
// recordRequest() is kept, and so is each LoadModel's client id (to see who asked).

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "support/fake_artifact.hpp"
#include "robodiff/server/service_api.hpp"

namespace robodiff::testing {

class FakeService : public server::ServiceApi {
 public:
  struct Record {
    std::string transport;
    rpc::Method method;
    StatusCode code;
  };
  static constexpr std::uint32_t kInputs = 3, kOutputs = 3;

  explicit FakeService(std::string instance_id, std::size_t threads = 2, std::size_t queue_capacity = 64)
      : instance_id_(std::move(instance_id)), capacity_(queue_capacity) {
    for (std::size_t i = 0; i < threads; ++i) workers_.emplace_back([this] { work(); });
  }
  ~FakeService() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
      queue_.clear();  // dropped, never run
    }
    cv_.notify_all();
    for (auto& t : workers_) t.join();
  }

  const std::string& instanceId() const override { return instance_id_; }

  Status admit(const rpc::RequestHeader& header) const override {
    return checkSchemaVersion(header.schema_version.major, header.schema_version.minor);
  }

  Status loadModel(const server::CallContext& ctx, const rpc::LoadModelRequest& request,
                   rpc::LoadModelReply& reply) override {
    {
      std::lock_guard lock(mutex_);
      load_model_clients_.emplace_back(ctx.client_id);
    }
    cv_.notify_all();
    if (request.urdf.rfind("sleep:", 0) == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(std::stoi(request.urdf.substr(6))));
    reply.model_id = "model:" + std::to_string(request.urdf.size()) + (request.floating_base ? ":floating:" : ":fixed:") +
                     request.options_json;
    reply.joint_names = {"shoulder", "elbow", "wrist \xc3\xa4"};
    reply.frame_names = {"base", "tool"};
    reply.nq = 7;
    reply.nv = 6;
    return {};
  }

  Status getFunction(const server::CallContext&, const rpc::GetFunctionRequest& request,
                     rpc::GetFunctionReply& reply) override {
    if (request.model_id.empty()) return {StatusCode::InvalidArgument, "model_id is empty"};
    reply.function_id = "fn-double";
    reply.state = request.wait ? rpc::FunctionState::Ready : rpc::FunctionState::Building;
    reply.inputs = {{"q", 1}, {"v", 1}, {request.spec_json, 1}};
    rpc::OutputBlock value{"value", rpc::OutputKind::Value, 2, 1, rpc::OutputLayout::DenseRowMajor, 2, {}, {}};
    rpc::OutputBlock jac{"jacobian", rpc::OutputKind::Jacobian, 2, 3, rpc::OutputLayout::SparseCsr, 1, {0, 1, 1}, {2}};
    reply.outputs = {value, jac};
    return {};
  }

  Status listFunctions(const server::CallContext&, const rpc::ListFunctionsRequest& request,
                       rpc::ListFunctionsReply& reply) override {
    reply.functions = {
        {"fn-double", request.model_id, "double", rpc::FunctionState::Ready, true, 12345678901ull, ""},
        {"fn-broken", request.model_id, "aba", rpc::FunctionState::Failed, false, 0, "compiler said no"}};
    return {};
  }

  Status health(const server::CallContext&, const rpc::HealthRequest& request, rpc::HealthReply& reply) override {
    reply.state = request.verbose ? rpc::ServingState::Draining : rpc::ServingState::Serving;
    reply.version = "0.1.0-test";
    reply.server_instance_id = instance_id_;
    reply.uptime_ns = 1ull << 40;
    reply.models_loaded = 1, reply.functions_loaded = 2, reply.functions_compiled = 3;
    reply.builds_queued = 4, reply.builds_running = 5, reply.builds_failed = 6, reply.builds_done = 7;
    reply.cache_hits = 8, reply.cache_misses = 9, reply.cache_bytes = 10, reply.cache_entries = 11;
    reply.workers_total = 12, reply.workers_busy = 13, reply.queue_depth = 14, reply.queue_capacity = 15;
    reply.batch_threads = 16;
    for (std::uint32_t m = 0; m < rpc::kMethodCount; ++m)
      reply.methods.push_back({static_cast<rpc::Method>(m), 100u + m, m, 1000u + m, 2000u + m, 3000u + m, 4000u + m});
    reply.errors = {{StatusCode::NotFound, 3}, {StatusCode::Unauthenticated, 1}};
    reply.transports = {{"dds", 42, 2}, {"iceoryx", 7, 0}};
    return {};
  }

  Status release(const server::CallContext&, const rpc::ReleaseRequest& request, rpc::ReleaseReply& reply) override {
    if (request.id != "fn-double") return {StatusCode::NotFound, "'" + request.id + "' is not loaded"};
    reply.references_left = 2;
    return {};
  }

  // FetchArtifactChunk: support/fake_artifact.hpp's artifact. QueryArtifact and FleetStatus
  // keep ServiceApi's defaults: not a build host, standalone.
  Status fetchArtifactChunk(const server::CallContext&, const rpc::FetchArtifactChunkRequest& request,
                            rpc::FetchArtifactChunkReply& reply) override {
    return testing::fakeArtifactChunk(request, reply);
  }

  Status shape(std::string_view function_id, server::FunctionShape& shape) override {
    if (function_id != "fn-double") return {StatusCode::NotFound, "function '" + std::string(function_id) + "' is not loaded"};
    shape = {kInputs, kOutputs, 100000};
    return {};
  }

  Status evaluate(const server::CallContext&, std::string_view, std::span<const double> inputs,
                  std::span<double> outputs) override {
    if (inputs.size() != kInputs || outputs.size() != kOutputs)
      return {StatusCode::InvalidArgument, "fn-double takes 3 inputs and 3 outputs, got " +
                                               std::to_string(inputs.size()) + " and " + std::to_string(outputs.size())};
    for (std::size_t i = 0; i < kInputs; ++i) outputs[i] = 2 * inputs[i];
    return {};
  }

  Status evaluateBatch(const server::CallContext& ctx, std::string_view, std::uint64_t knots,
                       std::span<const double> inputs, std::span<double> outputs) override {
    if (inputs.size() != knots * kInputs || outputs.size() != knots * kOutputs)
      return {StatusCode::InvalidArgument, "sizes do not add up"};
    if (ctx.expired()) return {StatusCode::DeadlineExceeded, "past the deadline"};
    for (std::size_t i = 0; i < inputs.size(); ++i) outputs[i] = 2 * inputs[i];
    return {};
  }

  bool post(std::function<void()> task) override {
    {
      std::lock_guard lock(mutex_);
      if (stopping_ || queue_.size() >= capacity_) return false;
      queue_.push_back(std::move(task));
    }
    cv_.notify_all();
    return true;
  }

  void recordRequest(std::string_view transport, rpc::Method method, StatusCode code,
                     std::chrono::nanoseconds) override {
    std::lock_guard lock(mutex_);
    records_.push_back({std::string(transport), method, code});
  }

  std::vector<Record> records() const {
    std::lock_guard lock(mutex_);
    return records_;
  }
  std::vector<std::string> loadModelClients() const {
    std::lock_guard lock(mutex_);
    return load_model_clients_;
  }
  // Waits until a LoadModel from `client_id` has started.
  bool waitLoadModelFrom(const std::string& client_id, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    return cv_.wait_for(lock, timeout, [&] {
      for (const auto& c : load_model_clients_)
        if (c == client_id) return true;
      return false;
    });
  }

 private:
  void work() {
    for (;;) {
      std::function<void()> task;
      {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
        if (stopping_) return;
        task = std::move(queue_.front());
        queue_.pop_front();
      }
      task();
    }
  }

  std::string instance_id_;
  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> queue_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
  std::vector<Record> records_;
  std::vector<std::string> load_model_clients_;
};

}  // namespace robodiff::testing
