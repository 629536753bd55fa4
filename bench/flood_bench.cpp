// Fair sharing under a flood (issue 19, item 5), one run, one table: robodiffd started
// here on its own cache (and RouDi, when none runs); the Panda RNEA Jacobian (arm7
// without ../shared) compiled; then 4 well-behaved clients (threads, each its own iceoryx
// client port) call Evaluate with a deadline for `--seconds`, first alone, then while
//   - one client floods garbage chunks (random bytes from a raw iceoryx client) as fast
//     as it can, on a session it opened (its own request queue, as every connection
//     has) or, with --garbage-port shared, on the shared port where sessions open, and
//   - another floods valid but expensive EvaluateBatch requests (`--knots` knots, 4
//     threads on one connection).
// Prints, per client and in all: unloaded calls/s, loaded calls/s, their ratio (target
// >= 0.5) and deadline misses (target 0).
//   build/bin/flood_bench [--robot URDF] [--seconds S] [--deadline-ms D] [--knots K] [--robodiffd PATH]
//                         [--flood both|garbage|batches] [--garbage-port session|shared]
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bench_daemon.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_client.hpp"
#include "robodiff/client/shm_connection.hpp"
#include "robodiff/schema/shm_codec.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;

namespace {

struct Load {
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> garbage_sent{0}, garbage_answered{0}, batches{0}, batch_errors{0};
};

struct ClientResult {
  std::uint64_t calls = 0, misses = 0, errors = 0;
};

// One well-behaved client: Evaluate in a loop for `seconds`, each with `deadline`.
ClientResult wellBehaved(const rpc::GetFunctionReply& function, double seconds, std::chrono::milliseconds deadline) {
  auto c = client::connectShm();
  const std::size_t in_n = rpc::inputCount(function), out_n = rpc::outputCount(function);
  std::vector<double> in(in_n), out(out_n);
  for (std::size_t i = 0; i < in_n; ++i) in[i] = 0.1 * std::sin(0.37 * i);
  for (int i = 0; i < 200; ++i) c->evaluate(function.function_id, in, out, {deadline});  // warm up
  ClientResult r;
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  while (Clock::now() < until) {
    const Status s = c->evaluate(function.function_id, in, out, {deadline});
    if (s.ok()) ++r.calls;
    else if (s.code == StatusCode::DeadlineExceeded) ++r.misses;
    else ++r.errors;
  }
  return r;
}

std::vector<ClientResult> measure(const rpc::GetFunctionReply& function, int clients, double seconds,
                                  std::chrono::milliseconds deadline) {
  std::vector<ClientResult> results(clients);
  std::vector<std::thread> threads;
  for (int k = 0; k < clients; ++k)
    threads.emplace_back([&, k] { results[k] = wellBehaved(function, seconds, deadline); });
  for (auto& t : threads) t.join();
  return results;
}

iox::popo::ClientOptions waiting() {  // robodiffd connects only clients that wait while its queue is full
  iox::popo::ClientOptions options;
  options.serverTooSlowPolicy = iox::popo::ConsumerTooSlowPolicy::WAIT_FOR_CONSUMER;
  return options;
}

// Opens a session by hand on the shared port (what connectShm does): its iceoryx event.
std::string openSession() {
  iox::popo::UntypedClient hello({"robodiff", "robodiff", "rpc"}, waiting());
  for (int i = 0; i < 3000 && hello.getConnectionState() != iox::ConnectionState::CONNECTED; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  auto loaned = hello.loan(static_cast<std::uint32_t>(shm::chunkSize(0, 0)), 8);
  if (loaned.has_error()) return "";
  rpc::RequestHeader header;
  header.client_id = "flooder";
  shm::writeSessionOpen(loaned.value(), header);
  if (hello.send(loaned.value()).has_error()) return "";
  for (int i = 0; i < 3000; ++i, std::this_thread::sleep_for(std::chrono::milliseconds(1))) {
    auto taken = hello.take();
    if (taken.has_error()) continue;
    shm::ReplyView view;
    const Status s = shm::parseSessionReply(
        taken.value(), iox::mepoo::ChunkHeader::fromUserPayload(taken.value())->userPayloadSize(), view);
    std::string event;
    if (s.ok() && view.header.status.ok()) event.assign(reinterpret_cast<const char*>(view.body.data()), view.body.size());
    hello.releaseResponse(taken.value());
    return event;
  }
  return "";
}

// Random bytes as requests, as fast as the queue takes them, on its own session or the
// shared port.
void floodGarbage(Load& load, bool on_session) {
  const std::string event = on_session ? openSession() : "rpc";
  if (event.empty()) return (void)std::fprintf(stderr, "flood_bench: the garbage flooder could not open a session\n");
  iox::popo::UntypedClient raw(
      {"robodiff", "robodiff", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event.c_str())}, waiting());
  std::mt19937_64 random(11);
  while (!load.stop.load()) {
    const std::uint32_t size = 16 + static_cast<std::uint32_t>(random() % 400);
    auto loaned = raw.loan(size, 8);
    if (!loaned.has_error()) {
      auto* words = static_cast<std::uint64_t*>(loaned.value());
      for (std::uint32_t i = 0; i < size / 8; ++i) words[i] = random();
      if (!raw.send(loaned.value()).has_error()) ++load.garbage_sent;
    }
    for (auto r = raw.take(); !r.has_error(); r = raw.take()) {
      ++load.garbage_answered;
      raw.releaseResponse(r.value());
    }
  }
}

// Valid, expensive requests: batches of `knots` knots from 4 threads on one connection.
void floodBatches(Load& load, const rpc::GetFunctionReply& function, int knots) {
  auto c = client::connectShm();
  const std::size_t in_n = rpc::inputCount(function), out_n = rpc::outputCount(function);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      std::vector<double> in(in_n * knots, 0.1), out(out_n * knots);
      while (!load.stop.load()) {
        if (c->evaluateBatch(function.function_id, knots, in, out).ok()) ++load.batches;
        else ++load.batch_errors;
      }
    });
  for (auto& t : threads) t.join();
}

void check(const Status& s, const char* what) {
  if (!s.ok()) {
    std::fprintf(stderr, "flood_bench: %s failed: %s: %s\n", what, toString(s.code).c_str(), s.message.c_str());
    std::exit(1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  fs::path robot = fs::path(ROBODIFF_SHARED_DIR) / "robots" / "panda_arm_fixed_fingers.urdf";
  if (!fs::exists(robot)) robot = fs::path(ROBODIFF_SOURCE_DIR) / "examples/robots/arm7.urdf";
  fs::path robodiffd = ROBODIFFD_PATH;
  std::string flood = "both", garbage_port = "session";
  double seconds = 5;
  int deadline_ms = 50, knots = 1000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--robot") robot = argv[i + 1];
    else if (a == "--seconds") seconds = std::atof(argv[i + 1]);
    else if (a == "--deadline-ms") deadline_ms = std::atoi(argv[i + 1]);
    else if (a == "--knots") knots = std::atoi(argv[i + 1]);
    else if (a == "--robodiffd") robodiffd = argv[i + 1];
    else if (a == "--flood") flood = argv[i + 1];
    else if (a == "--garbage-port") garbage_port = argv[i + 1];
  }
  const auto deadline = std::chrono::milliseconds(deadline_ms);
  const fs::path dir = fs::temp_directory_path() / ("robodiff-flood-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string uri = "file://" + (fs::path(ROBODIFF_SOURCE_DIR) / "deploy/cyclonedds-loopback.xml").string();
  setenv("CYCLONEDDS_URI", uri.c_str(), 1);
  constexpr int kClients = 4;
  std::vector<ClientResult> unloaded, loaded;
  Load load;
  {
    bench::Daemon daemon(robodiffd, dir / "cache", 1 + getpid() % 200, dir / "robodiffd.log");
    auto c = client::connectShm();
    rpc::LoadModelRequest load_request;
    load_request.urdf = bench::readText(robot);
    rpc::LoadModelReply model;
    check(c->loadModel(load_request, model), "LoadModel");
    rpc::GetFunctionRequest get;
    get.model_id = model.model_id;
    get.spec_json = bench::readText(fs::path(ROBODIFF_SOURCE_DIR) / "examples/specs/rnea_jacobian.json");
    get.wait = true;
    rpc::GetFunctionReply function;
    check(c->getFunction(get, function), "GetFunction");
    for (int i = 0;; ++i) {  // the compiled library, not the interpreter
      rpc::ListFunctionsReply list;
      check(c->listFunctions({}, list), "ListFunctions");
      if (!list.functions.empty() && list.functions[0].compiled) break;
      if (i > 1200) return std::fprintf(stderr, "flood_bench: not compiled within 120 s\n"), 1;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    std::printf("robot %s, RNEA Jacobian; %d well-behaved clients, %.1f s per phase, deadline %d ms; flood: %s "
                "(garbage on the %s port)\n",
                robot.stem().c_str(), kClients, seconds, deadline_ms, flood.c_str(), garbage_port.c_str());
    unloaded = measure(function, kClients, seconds, deadline);
    std::thread garbage([&] { if (flood != "batches") floodGarbage(load, garbage_port != "shared"); });
    std::thread batches([&] { if (flood != "garbage") floodBatches(load, function, knots); });
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    loaded = measure(function, kClients, seconds, deadline);
    load.stop = true;
    garbage.join();
    batches.join();
  }
  std::printf("\n| client | unloaded calls/s | loaded calls/s | ratio (target >= 0.5) | deadline misses (target 0) | errors |\n");
  std::printf("|---|---|---|---|---|---|\n");
  ClientResult u_all, l_all;
  for (int k = 0; k < kClients; ++k) {
    const double u = unloaded[k].calls / seconds, l = loaded[k].calls / seconds;
    std::printf("| %d | %.0f | %.0f | %.2f | %llu | %llu |\n", k + 1, u, l, l / u,
                static_cast<unsigned long long>(unloaded[k].misses + loaded[k].misses),
                static_cast<unsigned long long>(unloaded[k].errors + loaded[k].errors));
    u_all.calls += unloaded[k].calls, l_all.calls += loaded[k].calls;
    l_all.misses += unloaded[k].misses + loaded[k].misses, l_all.errors += unloaded[k].errors + loaded[k].errors;
  }
  std::printf("| all | %.0f | %.0f | %.2f | %llu | %llu |\n", u_all.calls / seconds, l_all.calls / seconds,
              static_cast<double>(l_all.calls) / u_all.calls, static_cast<unsigned long long>(l_all.misses),
              static_cast<unsigned long long>(l_all.errors));
  std::printf("\nflooders while loaded: %.0f garbage chunks/s (%llu answered: the error budget), "
              "%.1f batches of %d knots/s (%llu refused or failed)\n",
              load.garbage_sent.load() / (seconds + 0.5), static_cast<unsigned long long>(load.garbage_answered.load()),
              load.batches.load() / (seconds + 0.5), knots, static_cast<unsigned long long>(load.batch_errors.load()));
  fs::remove_all(dir);
  return 0;
}
