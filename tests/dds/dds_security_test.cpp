// DDS Security on the DDS transport, with real participants on loopback and a real keystore
// made by initKeystore/addIdentity (what `robodiff security` runs): an authenticated client
// is served; a participant without credentials can neither call nor listen; an identity of
// another CA and a tampered permissions document are refused.

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "dds_test_env.hpp"
#include "fake_service.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/dds_keystore.hpp"
#include "robodiff/server/dds_server.hpp"
#include "support/temp_dir.hpp"

extern char** environ;

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using client::DdsConnection;
using client::DdsConnectionOptions;
using client::IdentityRole;
using dds_codec::DdsSecurity;
using server::DdsServer;
using server::DdsServerOptions;
using testing::FakeService;

namespace fs = std::filesystem;

constexpr const char* kChildVariable = "ROBODIFF_DDS_SECURITY_CHILD";  // "<role> <domain> <keystore>/<identity>"
constexpr int kChildCalls = 5;

// In a child: Cyclone loads DDS Security per domain and process, so an open and a secure
// participant of one domain need two processes. "server": a secure server until killed;
// "client": kChildCalls LoadModels, exit status 0 when all were answered.
int runChildIfAsked() {
  const char* spec = std::getenv(kChildVariable);
  if (!spec) return 0;
  std::istringstream words(spec);
  std::string role, identity;
  std::uint32_t domain = 0;
  words >> role >> domain >> identity;
  try {
    const DdsSecurity security = dds_codec::securityFromSpec(identity);
    if (role == "server") {
      FakeService service("srv-secure");
      server::Logger log(stderr, server::LogLevel::Warn);
      DdsServerOptions options;
      options.domain_id = domain;
      options.security = security;
      DdsServer server(service, options, log);
      server.start();
      std::this_thread::sleep_for(60s);  // the parent kills it long before
    } else {
      DdsConnectionOptions options;
      options.domain_id = domain;
      options.security = security;
      options.match_timeout = 20s;
      DdsConnection client(options);
      for (int i = 0; i < kChildCalls; ++i) {
        rpc::LoadModelReply reply;
        if (!client.loadModel({"<robot/>", false, ""}, reply, client::CallOptions{20s}).ok()) _exit(3);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "security test child: %s\n", e.what());
    _exit(4);
  }
  _exit(0);
}
const int child_ran = runChildIfAsked();

// This test binary again, as a child (fork + exec: a clean DDS runtime); killed and reaped
// when it goes out of scope.
class Child {
 public:
  Child(const std::string& role, std::uint32_t domain, const fs::path& identity) {
    std::vector<std::string> env;
    for (char** e = environ; *e; ++e) env.emplace_back(*e);
    env.push_back(std::string(kChildVariable) + "=" + role + " " + std::to_string(domain) + " " + identity.string());
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
  ~Child() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  // The exit status, or -1 when it has not exited within `timeout`.
  int wait(std::chrono::milliseconds timeout) {
    int status = 0;
    const bool exited = testing::eventually([&] { return waitpid(pid_, &status, WNOHANG) == pid_; }, timeout);
    if (!exited) return -1;
    pid_ = 0;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  }

 private:
  pid_t pid_ = 0;
};

// Two keystores (two CAs) for the whole suite: making keys takes a few openssl runs.
struct Keystores {
  testing::TempDir dir;
  fs::path ours = dir / "keystore", theirs = dir / "other";
  Keystores() {
    client::initKeystore(ours);
    client::addIdentity(ours, "alice", IdentityRole::Client);
    client::initKeystore(theirs);
    client::addIdentity(theirs, "mallory", IdentityRole::Client);
  }
};

class DdsSecurityTest : public testing::DdsTest {
 protected:
  static void SetUpTestSuite() {
    (void)child_ran;
    testing::DdsTest::SetUpTestSuite();
    keys_ = new Keystores();
  }
  static void TearDownTestSuite() {
    delete keys_;
    keys_ = nullptr;
  }

  // A domain per test: this process's participants of one domain share one security setup.
  static std::uint32_t freshDomain() {
    static int next = 0;
    return static_cast<std::uint32_t>(1 + (getpid() + 37 * ++next) % 200);
  }
  std::unique_ptr<Child> startSecureServer() {
    return std::make_unique<Child>("server", domain_, keys_->ours / "robodiffd");
  }
  DdsConnectionOptions clientOptions(const DdsSecurity& security, std::chrono::milliseconds timeout) const {
    DdsConnectionOptions o;
    o.domain_id = domain_;
    o.security = security;
    o.connection.default_timeout = timeout;
    o.match_timeout = timeout;
    return o;
  }
  // A LoadModel that the fake service answers with "model:8:fixed:".
  static Status load(DdsConnection& client, rpc::LoadModelReply& reply) {
    return client.loadModel({"<robot/>", false, ""}, reply);
  }

  static inline Keystores* keys_ = nullptr;
  const std::uint32_t domain_ = freshDomain();
};

TEST_F(DdsSecurityTest, AuthenticatedClientIsServed) {
  auto server = startSecureServer();
  DdsConnection alice(clientOptions(dds_codec::keystoreIdentity(keys_->ours, "alice"), 15s));
  rpc::LoadModelReply reply;
  const Status s = load(alice, reply);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(reply.model_id, "model:8:fixed:");
}

TEST_F(DdsSecurityTest, ParticipantWithoutCredentialsCannotCall) {
  auto server = startSecureServer();
  DdsConnection open(clientOptions({}, 3s));
  rpc::LoadModelReply reply;
  const Status s = load(open, reply);
  EXPECT_EQ(s.code, StatusCode::Unavailable) << s.message;  // never matched with the server
  EXPECT_FALSE(open.connected());
}

TEST_F(DdsSecurityTest, ParticipantWithoutCredentialsCannotListen) {
  auto server = startSecureServer();
  // An open participant reading the reply topic while alice (another process) is served.
  dds_codec::DdsEndpoints eavesdropper(domain_, dds_codec::kDefaultServiceName, dds_codec::DdsEndpoints::Side::Client);
  Child alice("client", domain_, keys_->ours / "alice");
  ASSERT_EQ(alice.wait(30s), 0) << "alice was not served";
  void* samples[1] = {nullptr};
  dds_sample_info_t info;
  const dds_return_t taken = dds_take(eavesdropper.reader(), samples, &info, 1, 1);
  if (taken > 0) dds_return_loan(eavesdropper.reader(), samples, taken);
  EXPECT_EQ(taken, 0) << "an unauthenticated reader received a reply";
  dds_subscription_matched_status_t matched{};
  dds_get_subscription_matched_status(eavesdropper.reader(), &matched);
  EXPECT_EQ(matched.total_count, 0u);
}

TEST_F(DdsSecurityTest, IdentityOfAnotherCaIsRefused) {
  auto server = startSecureServer();
  DdsConnection mallory(clientOptions(dds_codec::keystoreIdentity(keys_->theirs, "mallory"), 3s));
  rpc::LoadModelReply reply;
  const Status s = load(mallory, reply);
  EXPECT_EQ(s.code, StatusCode::Unavailable) << s.message;
}

TEST_F(DdsSecurityTest, TamperedPermissionsAreRefused) {
  // alice's identity, with her signed permissions edited to let her read requests too.
  const fs::path eve = keys_->ours / "identities" / "eve";
  fs::create_directories(eve);
  for (const char* f : {"cert.pem", "key.pem", "permissions.p7s"})
    fs::copy_file(keys_->ours / "identities" / "alice" / f, eve / f, fs::copy_options::overwrite_existing);
  std::stringstream text;
  text << std::ifstream(eve / "permissions.p7s").rdbuf();
  std::string p7s = text.str();
  const std::string granted = "<topic>robodiff_reply</topic>";
  const auto at = p7s.find(granted);
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, granted.size(), "<topic>robodiff_*</topic>");
  std::ofstream(eve / "permissions.p7s", std::ios::trunc) << p7s;

  auto server = startSecureServer();
  const DdsSecurity security = dds_codec::keystoreIdentity(keys_->ours, "eve");
  try {
    DdsConnection tampered(clientOptions(security, 3s));
    ADD_FAILURE() << "a participant with tampered permissions was created";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("with DDS security (identity eve"), std::string::npos) << e.what();
  }
}

TEST_F(DdsSecurityTest, KeystoreNamesRolesAndRefusesDuplicates) {
  client::addIdentity(keys_->ours, "ops", IdentityRole::Operator);
  std::stringstream permissions;
  permissions << std::ifstream(keys_->ours / "identities" / "ops" / "permissions.xml").rdbuf();
  EXPECT_NE(permissions.str().find("<subject_name>CN=ops,OU=operators,O=robodiff</subject_name>"), std::string::npos);
  std::stringstream server;
  server << std::ifstream(keys_->ours / "identities" / "robodiffd" / "permissions.xml").rdbuf();
  EXPECT_NE(server.str().find("<publish><topics><topic>robodiff_reply</topic>"), std::string::npos) << server.str();
  EXPECT_THROW(client::addIdentity(keys_->ours, "alice", IdentityRole::Client), std::invalid_argument);
  EXPECT_THROW(client::addIdentity(keys_->ours, "../x", IdentityRole::Client), std::invalid_argument);
  EXPECT_THROW(client::initKeystore(keys_->ours), std::runtime_error);
  EXPECT_EQ(fs::status(keys_->ours / "private" / "ca.key.pem").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
}

TEST_F(DdsSecurityTest, MissingKeystoreFileIsNamed) {
  try {
    dds_codec::keystoreIdentity(keys_->ours, "nobody");
    FAIL() << "no error for a missing identity";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("identities/nobody/cert.pem"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace robodiff
