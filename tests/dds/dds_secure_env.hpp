#pragma once
// What the DDS Security tests share (dds_security_test, dds_caller_test,
// dds_reply_confinement_test): a keystore made by the project's own code (initKeystore /
// addIdentity, what `robodiff security` runs), a fresh domain per test, and this test
// binary run again as a child process in one role. Cyclone 0.10 sets security up per
// domain and process, so a secure server, an open participant and another identity's
// client of the same domain each need a process of their own.
//
// Child roles (ROBODIFF_DDS_CHILD="<role> <domain> <keystore>/<identity> | open"):
//   server  a CallerEchoService behind a DdsServer until killed; with a 4th word, a file
//           where it appends "<client id> <caller>" for every LoadModel it serves;
//   client  kDdsChildCalls LoadModels and Evaluates; exit status 0 when all were answered
//           correctly, 3 when one was not.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_env.hpp"
#include "fake_service.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/dds_keystore.hpp"
#include "robodiff/schema/dds_codec.hpp"
#include "robodiff/server/dds_server.hpp"
#include "support/temp_dir.hpp"

extern char** environ;

namespace robodiff::testing {

// FakeService whose LoadModel answers with who called: "<name>[+operator][+authenticated]",
// and, given a file, appends "<client id> <that answer>" to it (what the server saw).
class CallerEchoService : public FakeService {
 public:
  using FakeService::FakeService;
  Status loadModel(const server::CallContext& ctx, const rpc::LoadModelRequest&, rpc::LoadModelReply& reply) override {
    reply.model_id = ctx.caller.name + (ctx.caller.operator_ ? "+operator" : "") +
                     (ctx.caller.authenticated ? "+authenticated" : "");
    if (served_) {
      std::fprintf(served_, "%.*s %s\n", static_cast<int>(ctx.client_id.size()), ctx.client_id.data(),
                   reply.model_id.c_str());
      std::fflush(served_);
    }
    return {};
  }
  void recordServedTo(std::FILE* file) { served_ = file; }

 private:
  std::FILE* served_ = nullptr;
};

inline constexpr const char* kDdsChildVariable = "ROBODIFF_DDS_CHILD";
inline constexpr int kDdsChildCalls = 5;

// The security of a child's identity argument ("open": none).
inline dds_codec::DdsSecurity childSecurity(const std::string& identity) {
  return identity == "open" ? dds_codec::DdsSecurity{} : dds_codec::securityFromSpec(identity);
}

inline void runDdsChildServer(std::uint32_t domain, const std::string& identity, const std::string& served_log) {
  CallerEchoService service("srv-secure-env");
  if (!served_log.empty()) service.recordServedTo(std::fopen(served_log.c_str(), "a"));  // closed at exit
  server::Logger log(stderr, server::LogLevel::Warn);
  server::DdsServerOptions options;
  options.domain_id = domain;
  options.security = childSecurity(identity);
  server::DdsServer server(service, options, log);
  server.start();
  std::this_thread::sleep_for(std::chrono::seconds(60));  // the parent kills it long before
}

// Exit status 0 when every call was answered right.
inline int runDdsChildClient(std::uint32_t domain, const std::string& identity) {
  client::DdsConnectionOptions options;
  options.domain_id = domain;
  options.security = childSecurity(identity);
  options.match_timeout = std::chrono::seconds(20);
  client::DdsConnection client(options);
  const client::CallOptions patient{std::chrono::seconds(20)};
  for (int i = 0; i < kDdsChildCalls; ++i) {
    rpc::LoadModelReply reply;
    if (!client.loadModel({"<robot/>", false, ""}, reply, patient).ok() || reply.model_id.empty()) return 3;
    const double in[3] = {1.0 * i, 2, 3};
    double out[3] = {};
    if (!client.evaluate("fn-double", in, out, patient).ok() || out[0] != 2.0 * i) return 3;
  }
  return 0;
}

// In a child (ROBODIFF_DDS_CHILD set): runs its role and exits; else returns 0.
inline int runDdsChildIfAsked() {
  const char* spec = std::getenv(kDdsChildVariable);
  if (!spec) return 0;
  std::istringstream words(spec);
  std::string role, identity, served_log;
  std::uint32_t domain = 0;
  words >> role >> domain >> identity >> served_log;
  int status = 0;
  try {
    if (role == "server") runDdsChildServer(domain, identity, served_log);
    else status = runDdsChildClient(domain, identity);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "DDS test child (%s): %s\n", spec, e.what());
    _exit(4);
  }
  _exit(status);
}
inline const int kDdsChildRan = runDdsChildIfAsked();  // at start-up, before any test

// This test binary again as a child (fork + exec: a clean DDS runtime); killed and reaped
// when it goes out of scope. `identity`: "<keystore>/<name>" or "open"; `served_log`: the
// server's record of what it served (none when empty).
class DdsChild {
 public:
  DdsChild(const std::string& role, std::uint32_t domain, const std::string& identity,
           const std::string& served_log = {}) {
    std::vector<std::string> env;
    for (char** e = environ; *e; ++e) env.emplace_back(*e);
    env.push_back(std::string(kDdsChildVariable) + "=" + role + " " + std::to_string(domain) + " " + identity + " " +
                  served_log);
    std::vector<char*> envp;
    for (auto& e : env) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::string self = "/proc/self/exe", filter = "--gtest_filter=-*";
    char* argv[] = {self.data(), filter.data(), nullptr};
    pid_ = fork();
    if (pid_ == 0) {
      execve(self.c_str(), argv, envp.data());
      _exit(127);
    }
  }
  ~DdsChild() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  DdsChild(const DdsChild&) = delete;
  DdsChild& operator=(const DdsChild&) = delete;
  // The exit status, or -1 when it has not exited within `timeout`.
  int wait(std::chrono::milliseconds timeout) {
    int status = 0;
    const bool exited = eventually([&] { return waitpid(pid_, &status, WNOHANG) == pid_; }, timeout);
    if (!exited) return -1;
    pid_ = 0;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  }

 private:
  pid_t pid_ = 0;
};

// A keystore (CA, governance, server identity "robodiffd") with the given identities.
struct TestKeystore {
  struct Identity {
    const char* name;
    client::IdentityRole role;
  };
  TempDir dir;
  std::filesystem::path path = dir / "keystore";
  explicit TestKeystore(std::initializer_list<Identity> identities, const std::string& subdir = "keystore")
      : path(dir / subdir) {
    client::initKeystore(path);
    for (const Identity& i : identities) client::addIdentity(path, i.name, i.role);
  }
  // "<keystore>/<name>": a child's identity argument.
  std::string spec(const char* name) const { return (path / name).string(); }
  dds_codec::DdsSecurity security(const char* name) const { return dds_codec::keystoreIdentity(path, name); }
};

// A domain per test (a process's participants of one domain share one security setup),
// claimed like testDomain's (support/dds_domain.hpp): no other running test process
// uses it, so an open participant there meets this test's participants only.
inline std::uint32_t freshSecureDomain() { return claimDdsDomain(1, 200); }

// A reader of the reply topic (reply = true) or a writer of the request topic on the
// participant of `endpoints`, in `partitions` (none: the default partition), with the
// transport's QoS: the entity, or the negative DDS return code when it is refused (under
// DDS Security: by the participant's own access-control plugin).
inline dds_entity_t rawEndpoint(const dds_codec::DdsEndpoints& endpoints, bool reply,
                                const std::vector<std::string>& partitions) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  const std::string name = std::string(dds_codec::kDefaultServiceName) + (reply ? "_reply" : "_request");
  const dds_entity_t topic = dds_create_topic(endpoints.participant(),
                                              reply ? &robodiff_wire_Reply_desc : &robodiff_wire_Request_desc,
                                              name.c_str(), qos, nullptr);
  std::vector<const char*> names;
  for (const std::string& p : partitions) names.push_back(p.c_str());
  if (!names.empty()) dds_qset_partition(qos, static_cast<uint32_t>(names.size()), names.data());
  const dds_entity_t entity = topic < 0 ? topic
                              : reply   ? dds_create_reader(endpoints.participant(), topic, qos, nullptr)
                                        : dds_create_writer(endpoints.participant(), topic, qos, nullptr);
  dds_delete_qos(qos);
  return entity;
}

}  // namespace robodiff::testing
