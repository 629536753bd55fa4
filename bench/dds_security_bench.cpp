// DDS Security cost (issue 19): Evaluate round trips over DDS, open vs authenticated (DDS
// Security: signed and encrypted), in one run and one table. Two robodiffd children on
// loopback, each on a DDS domain of its own (Cyclone sets security up per domain and
// process): one open, one with a keystore made here by `robodiff security`'s code.
// Target: secure p50 at most 1.5x the open one. A third row: a keystore made with
// --protect-metadata (the RTPS submessages around the data encrypted too).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_daemon.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/dds_keystore.hpp"

namespace fs = std::filesystem;
using namespace robodiff;
using Clock = std::chrono::steady_clock;

namespace {

void check(const Status& s, const char* what) {
  if (s.ok()) return;
  std::fprintf(stderr, "dds_security_bench: %s: %s\n", what, s.message.c_str());
  std::exit(1);
}

// robodiffd on `domain` with extra --set options; SIGTERM at the end.
struct Server {
  pid_t pid = -1;
  Server(const fs::path& cache, int domain, const std::vector<std::string>& sets, const fs::path& log) {
    std::vector<std::string> args = {ROBODIFFD_PATH, "--cache", cache.string(), "--dds-domain",
                                     std::to_string(domain), "--no-iceoryx", "--no-http"};
    for (const auto& s : sets) args.insert(args.end(), {"--set", s});
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid = fork();
    if (pid == 0) {
      const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      dup2(fd, STDERR_FILENO);
      dup2(fd, STDOUT_FILENO);
      execv(argv[0], argv.data());
      _exit(127);
    }
    for (int i = 0; i < 1500; ++i) {
      if (bench::readText(log).find("\"event\":\"serving\"") != std::string::npos) return;
      if (waitpid(pid, nullptr, WNOHANG) == pid) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::fprintf(stderr, "robodiffd did not start; its log:\n%s\n", bench::readText(log).c_str());
    std::exit(1);
  }
  ~Server() {
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
  }
};

struct Function {
  std::string id;
  std::size_t inputs = 0, outputs = 0;
};

// LoadModel + GetFunction, then waits until the compiled library serves it.
Function prepare(client::Connection& c, const fs::path& robot, const fs::path& spec) {
  rpc::LoadModelRequest load;
  load.urdf = bench::readText(robot);
  rpc::LoadModelReply model;
  check(c.loadModel(load, model), "LoadModel");
  rpc::GetFunctionRequest get;
  get.model_id = model.model_id;
  get.spec_json = bench::readText(spec);
  get.wait = true;
  rpc::GetFunctionReply function;
  check(c.getFunction(get, function), "GetFunction");
  for (int i = 0;; ++i) {
    rpc::ListFunctionsReply list;
    check(c.listFunctions({}, list), "ListFunctions");
    if (!list.functions.empty() && list.functions[0].compiled) break;
    if (i > 1200) {
      std::fprintf(stderr, "dds_security_bench: the library was not compiled within 120 s\n");
      std::exit(1);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return {function.function_id, rpc::inputCount(function), rpc::outputCount(function)};
}

struct Percentiles {
  double p50, p90, p99;
};

// The latencies (us) of `calls` Evaluates, appended to `us`.
void roundTrips(client::Connection& c, const Function& f, int calls, std::vector<double>& us) {
  std::vector<double> in(f.inputs, 0.1), out(f.outputs);
  for (int i = 0; i < calls; ++i) {
    const auto t = Clock::now();
    check(c.evaluate(f.id, in, out), "Evaluate");
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t).count());
  }
}

Percentiles percentiles(std::vector<double> us) {
  std::sort(us.begin(), us.end());
  auto at = [&](double q) { return us[static_cast<std::size_t>(q * double(us.size() - 1))]; };
  return {at(0.5), at(0.9), at(0.99)};
}

}  // namespace

int main(int argc, char** argv) {
  int calls = 5000;
  for (int i = 1; i + 1 < argc; i += 2)
    if (std::string(argv[i]) == "--calls") calls = std::max(10, std::atoi(argv[i + 1]));
  const fs::path source(ROBODIFF_SOURCE_DIR);
  const fs::path robot = source / "examples/robots/arm7.urdf", spec = source / "examples/specs/rnea_jacobian.json";
  const fs::path dir = fs::temp_directory_path() / ("robodiff-dds-security-bench-" + std::to_string(getpid()));
  fs::create_directories(dir);
  setenv("CYCLONEDDS_URI", ("file://" + (source / "deploy/cyclonedds-loopback.xml").string()).c_str(), 1);
  const int base_domain = 1 + getpid() % 50;  // + 0, 50, 100: one domain per server

  client::initKeystore(dir / "keystore");
  client::addIdentity(dir / "keystore", "bench", client::IdentityRole::Client);
  client::KeystoreOptions protect;
  protect.protect_metadata = true;
  client::initKeystore(dir / "keystore-metadata", "robodiffd", protect);
  client::addIdentity(dir / "keystore-metadata", "bench", client::IdentityRole::Client, protect);

  // The servers run at once and are timed in alternating rounds, so that load from
  // elsewhere on the host weighs on all alike.
  constexpr int kRounds = 20;
  struct Mode {
    const char* label;
    fs::path keystore;  // none: open
    std::vector<double> us;
  };
  std::vector<Mode> modes = {{"open", {}, {}},
                             {"DDS Security: data encrypted", dir / "keystore", {}},
                             {"DDS Security: data and metadata encrypted", dir / "keystore-metadata", {}}};
  Function f;
  {
    std::vector<std::unique_ptr<Server>> servers;
    std::vector<std::unique_ptr<client::DdsConnection>> clients;
    for (std::size_t m = 0; m < modes.size(); ++m) {
      const int domain = base_domain + 50 * static_cast<int>(m);
      std::vector<std::string> sets;
      if (!modes[m].keystore.empty()) sets.push_back("dds.security=" + modes[m].keystore.string());
      servers.push_back(std::make_unique<Server>(dir / "cache", domain, sets, dir / ("server" + std::to_string(m) + ".log")));
      client::DdsConnectionOptions options;
      options.domain_id = static_cast<std::uint32_t>(domain);
      if (!modes[m].keystore.empty()) options.security = dds_codec::keystoreIdentity(modes[m].keystore, "bench");
      clients.push_back(std::make_unique<client::DdsConnection>(options));
      f = prepare(*clients.back(), robot, spec);  // compiled once, then cache hits
    }
    std::vector<double> warm_up;
    for (auto& c : clients) roundTrips(*c, f, calls / 5, warm_up);
    for (int round = 0; round < kRounds; ++round)
      for (std::size_t m = 0; m < modes.size(); ++m) roundTrips(*clients[m], f, calls / kRounds, modes[m].us);
  }  // the servers stop
  std::printf("Evaluate round trips over DDS on loopback, arm7 RNEA Jacobian (%zu in, %zu out), %d calls each,\n"
              "in %d alternating rounds\n\n",
              f.inputs, f.outputs, calls, kRounds);
  std::printf("| DDS                                       | p50 (us) | p90 (us) | p99 (us) | p50 / open |\n");
  std::printf("|-------------------------------------------|---------:|---------:|---------:|-----------:|\n");
  const double open_p50 = percentiles(modes[0].us).p50;
  for (const Mode& m : modes) {
    const Percentiles p = percentiles(m.us);
    std::printf("| %-41s | %8.1f | %8.1f | %8.1f | %9.2fx |\n", m.label, p.p50, p.p90, p.p99, p.p50 / open_p50);
  }
  const double ratio = percentiles(modes[1].us).p50 / open_p50;
  std::printf("\ndefault keystore (data encrypted) / open p50: %.2fx (target at most 1.5x): %s\n", ratio,
              ratio <= 1.5 ? "met" : "NOT met");
  fs::remove_all(dir);
  return 0;
}
