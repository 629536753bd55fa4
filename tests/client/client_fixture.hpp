// What the client tests share: one RouDi and one robodiffd (real processes) on a
// temporary cache, an iceoryx service and a DDS domain of this test process's own (so
// that servers of other test processes on the same RouDi never answer), and Client
// options pointing at them.
#pragma once

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "robodiff/client/client.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiffd/service_fixture.hpp"
#include "workers/worker_fixtures.hpp"

namespace robodiff::testing {

// An iceoryx service name of this process's own; `n` tells servers of one process apart.
inline std::string clientTestService(int n = 0) {
  return "robodiff-client-test-" + std::to_string(::getpid()) + "-" + std::to_string(n);
}

inline client::ClientOptions clientOptions(client::Mode mode, const std::filesystem::path& cache_dir,
                                           std::chrono::milliseconds timeout = std::chrono::seconds(10),
                                           const std::string& service = clientTestService()) {
  client::ClientOptions options;
  options.server.mode = mode;
  options.server.shm_service = service;
  options.server.dds_domain = testDomain();
  options.cache_dir = cache_dir;
  options.timeout = timeout;
  return options;
}

// A robodiffd on its own temporary cache; start() again after kill() for a restart.
class TestServer {
 public:
  TestServer() : service_(clientTestService(next())) {
    signal(SIGTERM, SIG_IGN);  // see end_to_end_test.cpp: RouDi's SIGTERM at exit
  }
  // Stopped cleanly (SIGTERM): a server left registered with a RouDi that is not ours
  // would outlive this process.
  ~TestServer() {
    if (server_) server_->terminate(std::chrono::seconds(10));
  }
  TestServer(const TestServer&) = delete;
  TestServer& operator=(const TestServer&) = delete;

  void start() {
    server_ = std::make_unique<RobodiffdProcess>(
        dir_ / "cache", dir_ / ("robodiffd-" + std::to_string(++starts_) + ".log"),
        std::vector<std::string>{"--roudi", "external", "--set", "iceoryx.service=" + service_});
    ASSERT_TRUE(server_->running());
  }
  void kill() { server_->kill(); }
  std::string log() const { return server_ ? server_->log() : std::string(); }
  std::filesystem::path cacheDir() const { return dir_ / "cache"; }
  client::ClientOptions options(client::Mode mode, std::chrono::milliseconds timeout = std::chrono::seconds(10)) const {
    return clientOptions(mode, cacheDir(), timeout, service_);
  }
  const std::string& service() const { return service_; }

 private:
  static int next() {
    static int n = 0;
    return n++;
  }
  std::string service_;
  TempDir dir_;
  RoudiProcess& roudi_ = sharedRoudi();
  std::unique_ptr<RobodiffdProcess> server_;
  int starts_ = 0;
};

// Whether the server says `function_id` is compiled (its library is in the cache).
inline bool serverCompiled(client::Client& c, const std::string& function_id) {
  try {
    for (const rpc::FunctionSummary& s : c.functions())
      if (s.function_id == function_id && s.compiled) return true;
  } catch (const client::ClientError&) {
  }
  return false;
}

// One robodiffd for the tests of this process that do not need their own, with the arm7
// RNEA Jacobian compiled into its cache.
class SharedServer {
 public:
  static SharedServer& get() {
    // Destroyed at exit, before the shared RouDi (constructed after it began).
    static SharedServer shared;
    return shared;
  }
  TestServer& server() { return server_; }
  const Model& model() const { return model_; }
  std::string function_id;

 private:
  SharedServer() : model_(loadUrdfString(arm7Text(), RootJoint::Fixed, "arm7.urdf")) {
    server_.start();
    client::Client c(server_.options(client::Mode::Shm));
    const client::ModelInfo m = c.loadModel(arm7Text());
    function_id = c.function(m, kRneaJacobianSpec).id();
    if (!waitFor([&] { return serverCompiled(c, function_id); }, std::chrono::seconds(120)))
      ADD_FAILURE() << "the server did not compile the arm7 RNEA Jacobian; log:\n" << server_.log();
  }
  TestServer server_;
  Model model_;
};

inline std::vector<double> outputsFor(const client::Function& f) { return std::vector<double>(f.outputCount(), std::nan("")); }

inline std::span<const double> spanOf(const Eigen::VectorXd& v) { return {v.data(), static_cast<std::size_t>(v.size())}; }

// `knots` random states of `model` for the RNEA Jacobian (q, v, a), knot after knot.
inline std::vector<double> randomRneaKnots(const Model& model, std::size_t knots, std::uint64_t seed) {
  const FunctionSpec spec = parseFunctionSpec(kRneaJacobianSpec);
  std::vector<double> in;
  for (std::size_t k = 0; k < knots; ++k)
    for (const Eigen::VectorXd& block : randomRuntimeInputs(model, spec, seed + k))
      in.insert(in.end(), block.data(), block.data() + block.size());
  return in;
}

}  // namespace robodiff::testing
