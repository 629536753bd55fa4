// Helpers shared by the service tests: a Service over a real cache in a temporary
// directory and real robodiff-worker processes, arm7 and small specs (built at -O0 for
// the generic target, to keep compiles short), and calls that return their replies.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "robodiff/server/log.hpp"
#include "robodiff/server/service.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::server::testing {

using robodiff::testing::readFile;
using robodiff::testing::sourceDir;
using robodiff::testing::TempDir;

// RNEA's value and its dense Jacobian wrt q, v, a.
inline const char* kRneaJacobianSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}],
        "build": {"optimization": "O0", "march_native": false}})";
// The same outputs with the Jacobian in CSR form (a layout worth comparing).
inline const char* kRneaSparseSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "sparse"}],
        "build": {"optimization": "O0", "march_native": false}})";
// RNEA's value only: the smallest function.
inline const char* kRneaValueSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"optimization": "O0", "march_native": false}})";

inline std::string arm7Urdf() { return readFile(sourceDir() / "examples/robots/arm7.urdf"); }

// `text` with the first occurrence of `from` replaced by `to` (which must be there).
inline std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "'" << from << "' not found";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

inline CallContext context() {
  CallContext ctx;
  ctx.transport = "inproc";
  ctx.client_id = "service-test";
  return ctx;
}

inline CallContext expiredContext() {
  CallContext ctx = context();
  ctx.deadline = Clock::now() - std::chrono::seconds(1);
  return ctx;
}

// Polls `condition` until it holds or `timeout` passes; returns whether it held.
inline bool waitFor(const std::function<bool()>& condition,
                    std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// A compiler that says it is cc (so keys are cc's) and compiles only once `gate` exists.
inline std::filesystem::path gatedCompiler(const TempDir& tmp, const std::filesystem::path& gate) {
  return tmp.script("gated-cc",
                    "case \"$1\" in --version|-v) exec cc \"$@\";; esac\n"
                    "while [ ! -e '" +
                        gate.string() +
                        "' ]; do sleep 0.02; done\n"
                        "exec cc \"$@\"\n");
}

// A compiler that fails like a real one.
inline std::filesystem::path failingCompiler(const TempDir& tmp) {
  return tmp.script("failing-cc",
                    "case \"$1\" in --version|-v) echo 'failing-cc 1.0'; exit 0;; esac\n"
                    "echo 'model.c:1:1: error: simulated failure' >&2\n"
                    "exit 1\n");
}

// A temporary directory with the cache and the log file, and Services over them.
class ServiceWorkspace {
 public:
  ServiceWorkspace() : log_file_(std::fopen((tmp / "service.log").c_str(), "w")), log(log_file_) {}
  ~ServiceWorkspace() {
    if (log_file_) std::fclose(log_file_);
  }
  ServiceWorkspace(const ServiceWorkspace&) = delete;
  ServiceWorkspace& operator=(const ServiceWorkspace&) = delete;

  ServiceOptions options(bool compile = false) const {
    ServiceOptions o;
    o.cache_dir = tmp / "cache";
    o.worker_executable = robodiff::testing::workerPath().string();
    o.build_workers = 1;
    o.compile = compile;
    o.request_threads = 2;
    o.batch_threads = 2;
    o.build_timeout = std::chrono::seconds(120);
    return o;
  }
  std::unique_ptr<Service> start(const ServiceOptions& o) { return std::make_unique<Service>(o, log); }

  // Everything logged so far.
  std::string logText() {
    std::fflush(log_file_);
    return readFile(tmp / "service.log");
  }

  TempDir tmp;

 private:
  std::FILE* log_file_;

 public:
  Logger log;
};

// LoadModel; fails the test unless OK.
inline rpc::LoadModelReply loadModel(Service& service, const std::string& urdf, bool floating_base = false) {
  rpc::LoadModelRequest request;
  request.urdf = urdf;
  request.floating_base = floating_base;
  rpc::LoadModelReply reply;
  const Status status = service.loadModel(context(), request, reply);
  EXPECT_TRUE(status.ok()) << toString(status.code) << ": " << status.message;
  return reply;
}

inline Status getFunction(Service& service, const std::string& model_id, const std::string& spec, bool wait,
                          rpc::GetFunctionReply& reply) {
  rpc::GetFunctionRequest request;
  request.model_id = model_id;
  request.spec_json = spec;
  request.wait = wait;
  return service.getFunction(context(), request, reply);
}

// GetFunction with wait; fails the test unless READY.
inline rpc::GetFunctionReply readyFunction(Service& service, const std::string& model_id, const std::string& spec) {
  rpc::GetFunctionReply reply;
  const Status status = getFunction(service, model_id, spec, true, reply);
  EXPECT_TRUE(status.ok()) << toString(status.code) << ": " << status.message;
  EXPECT_EQ(reply.state, rpc::FunctionState::Ready);
  return reply;
}

inline rpc::FunctionSummary summaryOf(Service& service, const std::string& function_id) {
  rpc::ListFunctionsReply list;
  EXPECT_TRUE(service.listFunctions(context(), {}, list).ok());
  for (const rpc::FunctionSummary& f : list.functions)
    if (f.function_id == function_id) return f;
  ADD_FAILURE() << "function " << function_id << " is not listed";
  return {};
}

inline rpc::HealthReply health(Service& service) {
  rpc::HealthReply reply;
  const Status status = service.health(context(), {}, reply);
  EXPECT_TRUE(status.ok()) << status.message;
  return reply;
}

// One knot of function `f`, or a failure of the test.
inline std::vector<double> evaluateOnce(Service& service, const rpc::GetFunctionReply& f,
                                        const std::vector<double>& in) {
  std::vector<double> out(rpc::outputCount(f), 0.0);
  const Status status = service.evaluate(context(), f.function_id, in, out);
  EXPECT_TRUE(status.ok()) << toString(status.code) << ": " << status.message;
  return out;
}

// Deterministic inputs in [-1, 1] (a small LCG: the same on every machine).
inline std::vector<double> someInputs(std::size_t n, std::uint64_t seed) {
  std::vector<double> x(n);
  std::uint64_t s = seed * 6364136223846793005ULL + 1442695040888963407ULL;
  for (double& v : x) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    v = static_cast<double>(s >> 11) / static_cast<double>(1ULL << 53) * 2.0 - 1.0;
  }
  return x;
}

// |a - b| <= tol * max(1, |a|, |b|), element by element.
inline ::testing::AssertionResult closeTo(const std::vector<double>& a, const std::vector<double>& b, double tol) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " and " << b.size();
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double scale = std::max({1.0, std::fabs(a[i]), std::fabs(b[i])});
    if (!(std::fabs(a[i] - b[i]) <= tol * scale))
      return ::testing::AssertionFailure() << "entry " << i << ": " << a[i] << " against " << b[i];
  }
  return ::testing::AssertionSuccess();
}

}  // namespace robodiff::server::testing
