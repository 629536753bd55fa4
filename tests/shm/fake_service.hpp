// A small ServiceApi for the iceoryx transport tests (the real Service lives in
// server/service): every method answers from fixed data, so the tests check the transport.
//
// Functions: "double" (3 in, 3 out: outputs = 2 * inputs), "big" (1 in, 4000 out: replies
// of 1000 knots exceed the shared-memory limit), "slow" (like "double", 300 ms per call).
// LoadModel with urdf "slow:<ms>" sleeps that long. post() runs tasks on `threads`
// threads with a queue of `queue_capacity`.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "support/fake_artifact.hpp"
#include "robodiff/server/service_api.hpp"

namespace robodiff::testing {

class FakeService : public server::ServiceApi {
 public:
  explicit FakeService(unsigned threads = 4, std::size_t queue_capacity = 64) : capacity_(queue_capacity) {
    for (unsigned i = 0; i < threads; ++i) workers_.emplace_back([this] { work(); });
  }
  ~FakeService() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    cv_.notify_all();
    for (auto& t : workers_) t.join();
  }

  const std::string& instanceId() const override { return id_; }

  Status admit(const rpc::RequestHeader& header) const override {
    if (!header.server_instance_id.empty() && header.server_instance_id != id_)
      return {StatusCode::NotFound, "request for server " + header.server_instance_id};
    return checkSchemaVersion(header.schema_version.major, header.schema_version.minor);
  }

  Status loadModel(const server::CallContext& ctx, const rpc::LoadModelRequest& request,
                   rpc::LoadModelReply& reply) override {
    ++started_slow_;
    if (request.urdf.rfind("slow:", 0) == 0) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(std::stoi(request.urdf.substr(5)));
      while (std::chrono::steady_clock::now() < until) {
        if (ctx.expired()) return {StatusCode::DeadlineExceeded, "LoadModel ran out of time"};
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
    reply.model_id = "model-" + std::to_string(request.urdf.size()) + (request.floating_base ? "-ff" : "") +
                     "-" + request.options_json;
    reply.joint_names = {"shoulder", "elbow", "wrist"};
    reply.frame_names = {"base", "tool", ""};
    reply.nq = request.floating_base ? 10 : 3;
    reply.nv = request.floating_base ? 9 : 3;
    return {};
  }

  Status getFunction(const server::CallContext&, const rpc::GetFunctionRequest& request,
                     rpc::GetFunctionReply& reply) override {
    if (request.model_id.empty()) return {StatusCode::InvalidArgument, "model_id is empty"};
    reply.function_id = "double";
    reply.state = request.wait ? rpc::FunctionState::Ready : rpc::FunctionState::Building;
    reply.inputs = {{"q", 2}, {"v", 1}};
    rpc::OutputBlock value{"value", rpc::OutputKind::Value, 1, 1, rpc::OutputLayout::DenseRowMajor, 1, {}, {}};
    rpc::OutputBlock jac{"jacobian", rpc::OutputKind::Jacobian, 2, 3, rpc::OutputLayout::SparseCsr, 2, {0, 1, 2}, {0, 2}};
    reply.outputs = {value, jac};
    return {};
  }

  Status listFunctions(const server::CallContext&, const rpc::ListFunctionsRequest& request,
                       rpc::ListFunctionsReply& reply) override {
    reply.functions = {{"double", request.model_id, "rnea", rpc::FunctionState::Ready, true, 42, ""},
                       {"bad", request.model_id, "aba", rpc::FunctionState::Failed, false, 0, "compiler crashed"}};
    return {};
  }

  Status health(const server::CallContext&, const rpc::HealthRequest&, rpc::HealthReply& reply) override {
    reply.state = rpc::ServingState::Serving;
    reply.version = "0.1.0-test";
    reply.server_instance_id = id_;
    reply.uptime_ns = 123456789;
    reply.models_loaded = 1;
    reply.functions_loaded = 2;
    reply.cache_bytes = 1ull << 40;
    reply.queue_capacity = static_cast<std::uint32_t>(capacity_);
    reply.methods = {{rpc::Method::Evaluate, 10, 1, 100, 200, 300, 400}};
    reply.errors = {{StatusCode::NotFound, 3}};
    reply.transports = {{"iceoryx", requests_.load(), 0}};
    return {};
  }

  Status release(const server::CallContext&, const rpc::ReleaseRequest& request, rpc::ReleaseReply& reply) override {
    if (request.id == "unknown") return {StatusCode::NotFound, "no model or function 'unknown'"};
    reply.references_left = static_cast<std::uint32_t>(request.id.size());
    return {};
  }

  // FetchArtifactChunk: support/fake_artifact.hpp's artifact. QueryArtifact and FleetStatus
  // keep ServiceApi's defaults: not a build host, standalone.
  Status fetchArtifactChunk(const server::CallContext&, const rpc::FetchArtifactChunkRequest& request,
                            rpc::FetchArtifactChunkReply& reply) override {
    return testing::fakeArtifactChunk(request, reply);
  }

  Status shape(std::string_view function_id, server::FunctionShape& shape) override {
    if (function_id == "double" || function_id == "slow") shape = {3, 3, 2'000'000};
    else if (function_id == "big") shape = {1, 4000, 100'000};
    else return {StatusCode::NotFound, "no function '" + std::string(function_id) + "'"};
    return {};
  }

  Status evaluate(const server::CallContext& ctx, std::string_view function_id, std::span<const double> inputs,
                  std::span<double> outputs) override {
    return evaluateBatch(ctx, function_id, 1, inputs, outputs);
  }

  Status evaluateBatch(const server::CallContext& ctx, std::string_view function_id, std::uint64_t knots,
                       std::span<const double> inputs, std::span<double> outputs) override {
    server::FunctionShape s;
    if (Status st = shape(function_id, s); !st.ok()) return st;
    if (inputs.size() != knots * s.input_count)
      return {StatusCode::InvalidArgument, "expected " + std::to_string(knots * s.input_count) + " inputs, got " +
                                               std::to_string(inputs.size())};
    if (outputs.size() != knots * s.output_count) return {StatusCode::InvalidArgument, "wrong output size"};
    if (function_id == "slow") std::this_thread::sleep_for(std::chrono::milliseconds(300));
    if (ctx.expired()) return {StatusCode::DeadlineExceeded, "evaluation ran out of time"};
    for (std::size_t i = 0; i < outputs.size(); ++i) outputs[i] = 2.0 * inputs[i % inputs.size()];
    return {};
  }

  bool post(std::function<void()> task) override {
    {
      std::lock_guard lock(mutex_);
      if (stopping_ || queue_.size() >= capacity_) return false;
      queue_.push_back(std::move(task));
    }
    cv_.notify_one();
    return true;
  }

  void recordRequest(std::string_view transport, rpc::Method, StatusCode code, std::chrono::nanoseconds) override {
    ++requests_;
    std::lock_guard lock(mutex_);
    ++codes_[code];
    last_transport_ = std::string(transport);
  }

  std::uint64_t requests() const { return requests_.load(); }
  std::uint64_t count(StatusCode code) {
    std::lock_guard lock(mutex_);
    return codes_[code];
  }
  std::uint64_t loadModelsStarted() const { return started_slow_.load(); }

 private:
  void work() {
    for (;;) {
      std::function<void()> task;
      {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
        if (queue_.empty()) return;
        task = std::move(queue_.front());
        queue_.pop_front();
      }
      task();
    }
  }

  std::string id_ = "fake-server-1";
  std::size_t capacity_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> queue_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
  std::atomic<std::uint64_t> requests_{0};
  std::atomic<std::uint64_t> started_slow_{0};
  std::map<StatusCode, std::uint64_t> codes_;
  std::string last_transport_;
};

}  // namespace robodiff::testing
