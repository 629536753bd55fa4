// A robodiffd client in a page: connect (iceoryx shared memory and/or DDS), load a robot,
// get its RNEA Jacobian, evaluate it once and 2,000 times, evaluate a batch of 1,000, and print
// what Health says. scripts/run.sh runs it against a robodiffd started on its defaults.
//
//   service_demo [--transport iceoryx|dds|both] [--urdf FILE] [--spec FILE] [--dds-domain N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/shm_connection.hpp"

using namespace robodiff;
using Clock = std::chrono::steady_clock;

namespace {

std::string readText(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "service_demo: cannot read %s\n", path.c_str());
    std::exit(2);
  }
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool ok(const Status& s, const char* what) {
  if (s.ok()) return true;
  std::fprintf(stderr, "  %s: %s: %s\n", what, toString(s.code).c_str(), s.message.c_str());
  return false;
}

double micros(Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

bool demo(client::Connection& c, const std::string& urdf, const std::string& spec) {
  std::printf("== over %s\n", std::string(c.transport()).c_str());
  rpc::LoadModelRequest load;
  load.urdf = urdf;
  rpc::LoadModelReply model;
  const auto tl = Clock::now();
  if (!ok(c.loadModel(load, model), "LoadModel")) return false;
  std::printf("  LoadModel: model %.16s..., nq %u, nv %u, %zu joints, in %.1f ms\n", model.model_id.c_str(), model.nq,
              model.nv, model.joint_names.size(), micros(Clock::now() - tl) / 1e3);

  rpc::GetFunctionRequest get;
  get.model_id = model.model_id;
  get.spec_json = spec;
  get.wait = true;
  rpc::GetFunctionReply function;
  const auto t0 = Clock::now();
  if (!ok(c.getFunction(get, function), "GetFunction")) return false;
  std::printf("  GetFunction: %s %s in %.1f ms; inputs", function.function_id.c_str(), rpc::toString(function.state),
              micros(Clock::now() - t0) / 1e3);
  for (const rpc::InputBlock& b : function.inputs) std::printf(" %s[%u]", b.name.c_str(), b.size);
  std::printf(", outputs");
  for (const rpc::OutputBlock& b : function.outputs) std::printf(" %s %ux%u", b.name.c_str(), b.rows, b.cols);
  std::printf("\n");

  const std::size_t in_n = rpc::inputCount(function), out_n = rpc::outputCount(function);
  std::vector<double> in(in_n), out(out_n);
  for (std::size_t i = 0; i < in_n; ++i) in[i] = 0.3 * std::sin(1.0 + i);
  if (!ok(c.evaluate(function.function_id, in, out), "Evaluate")) return false;
  std::printf("  Evaluate: value[0..%u) =", std::min(4u, function.outputs.at(0).nnz));
  for (std::uint32_t i = 0; i < std::min(4u, function.outputs.at(0).nnz); ++i) std::printf(" %.6f", out[i]);
  std::printf(" ...\n");

  auto compiled = [&] {
    rpc::ListFunctionsReply list;
    if (!c.listFunctions({}, list).ok()) return false;
    for (const rpc::FunctionSummary& f : list.functions)
      if (f.function_id == function.function_id) return f.compiled;
    return false;
  };
  auto timeCalls = [&] {
    std::vector<double> us;
    for (int i = 0; i < 2000; ++i) {
      const auto t = Clock::now();
      if (!ok(c.evaluate(function.function_id, in, out), "Evaluate")) return false;
      us.push_back(micros(Clock::now() - t));
    }
    std::sort(us.begin(), us.end());
    std::printf("  Evaluate x2000 (%s): p50 %.1f us, p99 %.1f us round trip\n",
                compiled() ? "compiled library" : "interpreter", us[us.size() / 2], us[us.size() * 99 / 100]);
    return true;
  };
  if (!timeCalls()) return false;
  if (!compiled()) {
    // The interpreter served from the moment the function was traced; the compiled
    // library is being built by a worker and swapped in when ready.
    const auto tc = Clock::now();
    while (!compiled() && Clock::now() - tc < std::chrono::seconds(120))
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    std::printf("  compiled library swapped in %.1f s later\n", micros(Clock::now() - tc) / 1e6);
    if (!timeCalls()) return false;
  }

  constexpr int kKnots = 1000;
  std::vector<double> batch_in(kKnots * in_n), batch_out(kKnots * out_n);
  for (std::size_t i = 0; i < batch_in.size(); ++i) batch_in[i] = 0.3 * std::sin(0.1 * i);
  const auto tb = Clock::now();
  if (!ok(c.evaluateBatch(function.function_id, kKnots, batch_in, batch_out), "EvaluateBatch")) return false;
  const double batch_us = micros(Clock::now() - tb);
  std::printf("  EvaluateBatch: %d knots in %.0f us round trip, %.2f us per knot\n", kKnots, batch_us,
              batch_us / kKnots);

  rpc::ListFunctionsReply list;
  if (!ok(c.listFunctions({}, list), "ListFunctions")) return false;
  for (const rpc::FunctionSummary& f : list.functions)
    std::printf("  ListFunctions: %s %s %s, %s, %llu knots evaluated\n", f.function_id.c_str(),
                f.function_name.c_str(), rpc::toString(f.state), f.compiled ? "compiled" : "interpreted",
                static_cast<unsigned long long>(f.evaluations));

  rpc::HealthReply h;
  if (!ok(c.health({}, h), "Health")) return false;
  std::printf("  Health: %s, robodiff %s, up %.1f s, %u models, %u functions (%u compiled), builds %u queued %u running "
              "%u done %u failed, cache %llu hits %llu misses %llu entries\n",
              rpc::toString(h.state), h.version.c_str(), h.uptime_ns / 1e9, h.models_loaded, h.functions_loaded,
              h.functions_compiled, h.builds_queued, h.builds_running, h.builds_done, h.builds_failed,
              static_cast<unsigned long long>(h.cache_hits), static_cast<unsigned long long>(h.cache_misses),
              static_cast<unsigned long long>(h.cache_entries));
  for (const rpc::MethodStats& m : h.methods)
    if (m.requests > 0)
      std::printf("    %-14s %6llu requests %4llu errors  p50 %.1f us  p99 %.1f us (server side)\n",
                  rpc::toString(m.method), static_cast<unsigned long long>(m.requests),
                  static_cast<unsigned long long>(m.errors), m.p50_ns / 1e3, m.p99_ns / 1e3);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string transport = "both";
  std::string urdf_path = std::string(ROBODIFF_SOURCE_DIR) + "/examples/robots/arm7.urdf";
  std::string spec_path = std::string(ROBODIFF_SOURCE_DIR) + "/examples/specs/rnea_jacobian.json";
  int domain = -1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--transport") transport = argv[i + 1];
    else if (a == "--urdf") urdf_path = argv[i + 1];
    else if (a == "--spec") spec_path = argv[i + 1];
    else if (a == "--dds-domain") domain = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: service_demo [--transport iceoryx|dds|both] [--urdf FILE] [--spec FILE] [--dds-domain N]\n");
      return 2;
    }
  }
  const std::string urdf = readText(urdf_path), spec = readText(spec_path);
  bool good = true;
  if (transport == "iceoryx" || transport == "both") {
    client::ShmConnectionOptions options;
    Status status;
    auto c = client::connectShm(options, status);
    good = c ? demo(*c, urdf, spec) && good : ok(status, "connect (iceoryx)");
  }
  if (transport == "dds" || transport == "both") {
    client::DdsConnectionOptions options;
    if (domain >= 0) options.domain_id = static_cast<std::uint32_t>(domain);
    auto c = client::connectDds(options);
    good = demo(*c, urdf, spec) && good;
  }
  return good ? 0 : 1;
}
