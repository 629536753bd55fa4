// A fleet on this machine for the tests: build hosts and robot hosts as real robodiffd
// processes (own caches, own configuration, DDS on loopback in the test's domain), a key
// pair the build hosts sign with, and a client of the robot (DDS service "robodiff").
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/client/client.hpp"
#include "robodiffd/robodiffd_process.hpp"
#include "robodiffd/service_fixture.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::testing {

// The fleet's DDS domain: one no other test uses (testDomain() gives 1..200 by process id,
// tests/dds 201..229), so that no other test's client meets these robodiffds, whose service
// is the default "robodiff". The fleet tests run one at a time (the roudi lock). 230: the
// last domain a DDS Security governance may name (Cyclone refuses 231 and 232 there).
inline const bool kFleetDomainChosen = ::setenv("ROBODIFF_TEST_DDS_DOMAIN", "230", 1) == 0;

// RNEA and its Jacobian for this CPU (the default -march=native): a robot asks its build
// hosts for its own x86-64 level instead. O1 keeps the builds short.
inline const char* kFleetSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}],
        "build": {"optimization": "O1"}})";

class FleetHosts {
 public:
  FleetHosts() {
    cache::SigningKey::generate().writePair(dir_.path() / "keys", "build");
    cache::SigningKey::generate().writePair(dir_.path() / "other", "stranger");
  }
  std::filesystem::path path() const { return dir_.path(); }
  std::filesystem::path signingKey() const { return dir_.path() / "keys/build.key"; }
  std::filesystem::path publicKey() const { return dir_.path() / "keys/build.pub"; }
  std::filesystem::path strangerKey() const { return dir_.path() / "other/stranger.pub"; }

  // A build host serving DDS service `service`; `extra`: more --set values.
  std::unique_ptr<RobodiffdProcess> buildHost(const std::string& service, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"--no-iceoryx", "--no-http", "--set", "dds.service=" + service,
                                     "--set", "fleet.role=build", "--set", "fleet.signing_key=" + signingKey().string()};
    for (const std::string& e : extra) args.insert(args.end(), {"--set", e});
    return std::make_unique<RobodiffdProcess>(dir_.path() / (service + "-cache"), dir_.path() / (service + ".log"),
                                              args);
  }

  // A robot host that compiles nothing, asks `build_hosts` ("a, b") and trusts `trusted`.
  std::unique_ptr<RobodiffdProcess> robot(const std::string& name, const std::string& build_hosts,
                                          const std::filesystem::path& trusted, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"--no-iceoryx", "--no-http", "--interpreter-only",
                                     "--set", "fleet.role=robot",
                                     "--set", "fleet.build_hosts=" + build_hosts,
                                     "--set", "fleet.trusted_keys=" + trusted.string(),
                                     "--set", "fleet.call_timeout=2s"};
    for (const std::string& e : extra) args.insert(args.end(), {"--set", e});
    return std::make_unique<RobodiffdProcess>(robotCache(name), dir_.path() / (name + ".log"), args);
  }
  std::filesystem::path robotCache(const std::string& name) const { return dir_.path() / (name + "-cache"); }

 private:
  TempDir dir_;
};

// A client of the robot host over DDS (or Local mode on `cache_dir`).
inline client::ClientOptions robotClientOptions(client::Mode mode = client::Mode::Dds,
                                                const std::filesystem::path& cache_dir = {}) {
  client::ClientOptions o;
  o.server.mode = mode;
  o.server.dds_domain = testDomain();
  o.cache_dir = cache_dir;
  o.server.shm_service = "fleet-nobody-" + std::to_string(::getpid());  // Local: the robot over DDS, no RouDi
  o.timeout = std::chrono::seconds(30);
  return o;
}

// Waits until the robot serves function `function_id` compiled (true) or `timeout` passes.
inline bool waitCompiled(client::Client& c, const std::string& function_id, std::chrono::seconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    for (const rpc::FunctionSummary& f : c.functions())
      if (f.function_id == function_id && f.compiled) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

// Waits until the robot's FleetStatus satisfies `done` (true) or `timeout` passes.
template <class Done>
bool waitFleet(client::Client& c, Done done, std::chrono::seconds timeout, rpc::FleetFigures* last = nullptr) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const rpc::FleetFigures f = c.fleetStatus().fleet;
    if (last != nullptr) *last = f;
    if (done(f)) return true;
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

// How many log lines of `event` a robodiffd wrote.
inline std::size_t countEvents(const std::string& log, const std::string& event) {
  std::size_t n = 0;
  for (std::size_t at = log.find("\"event\":\"" + event + "\""); at != std::string::npos;
       at = log.find("\"event\":\"" + event + "\"", at + 1))
    ++n;
  return n;
}

// The entries of a cache directory (opened read-write: the robot has stopped or shares it).
inline std::vector<cache::Entry> cacheEntries(const std::filesystem::path& dir) {
  return cache::Cache::open(dir).list();
}

}  // namespace robodiff::testing
