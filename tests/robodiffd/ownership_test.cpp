// Ownership end to end: a real robodiffd serving DDS Security with a keystore made by
// `robodiff security`, and three identities each in its own process (the CLI, or this
// binary as a child): alice submits a job and gets a function; bob can neither see the
// job's status or result, nor cancel it, nor see or release alice's function; ops (an
// operator) can do all of it.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "robodiff/client/dds_connection.hpp"
#include "robodiff/schema/dds_security.hpp"
#include "robodiffd/robodiffd_process.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using json = nlohmann::json;

constexpr const char* kReleaseChild = "ROBODIFF_OWNERSHIP_RELEASE";  // "<domain> <keystore>/<identity> <id>"

// In a child: Release <id> as the identity, printing the status code's name. (The CLI has
// no release command; one DDS Security identity per process and domain.)
int releaseIfAsked() {
  const char* spec = std::getenv(kReleaseChild);
  if (!spec) return 0;
  std::istringstream words(spec);
  std::uint32_t domain = 0;
  std::string identity, id;
  words >> domain >> identity >> id;
  try {
    client::DdsConnectionOptions options;
    options.domain_id = domain;
    options.security = dds_codec::securityFromSpec(identity);
    options.match_timeout = std::chrono::seconds(20);
    options.connection.default_timeout = std::chrono::seconds(20);
    client::DdsConnection connection(options);
    rpc::ReleaseReply reply;
    const Status s = connection.release({id}, reply);
    std::printf("%s %u %s\n", toString(s.code).c_str(), reply.references_left, s.message.c_str());
  } catch (const std::exception& e) {
    std::printf("EXCEPTION %s\n", e.what());
  }
  std::fflush(stdout);
  _exit(0);
}
const int release_ran = releaseIfAsked();

std::string selfPath() {
  char path[4096] = {};
  const ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
  return n > 0 ? std::string(path, static_cast<std::size_t>(n)) : std::string();
}

class Ownership : public ::testing::Test {
 protected:
  void SetUp() override {
    (void)release_ran;
    keystore_ = (dir_ / "keystore").string();
    const ProcessResult r = runCommand(cli("security init " + shellQuote(keystore_)) + " && " +
                                       cli("security add-client " + shellQuote(keystore_) + " alice") + " && " +
                                       cli("security add-client " + shellQuote(keystore_) + " bob") + " && " +
                                       cli("security add-client " + shellQuote(keystore_) + " ops --operator"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    server_ = std::make_unique<RobodiffdProcess>(
        dir_ / "cache", dir_ / "robodiffd.log",
        std::vector<std::string>{"--no-iceoryx", "--no-http", "--set", "dds.security=" + keystore_, "--set",
                                 "jobs.data_dirs=" + (sourceDir() / "examples").string() + ":" + dir_.path().string()});
    ASSERT_TRUE(server_->running());
  }

  static std::string cli(const std::string& args) { return shellQuote(cliPath().string()) + " " + args; }
  // The CLI as `identity` against this server.
  ProcessResult as(const std::string& identity, const std::string& args) const {
    return runCommand("ROBODIFF_DDS_SECURITY=" + shellQuote(keystore_ + "/" + identity) + " " +
                      cli(args + " --server dds:" + std::to_string(testDomain()) + " --timeout 30"));
  }
  // Release as `identity` (a child process): "<STATUS> <references_left> <message>".
  std::string releaseAs(const std::string& identity, const std::string& id) const {
    return runCommand(std::string(kReleaseChild) + "=" +
                      shellQuote(std::to_string(testDomain()) + " " + keystore_ + "/" + identity + " " + id) + " " +
                      shellQuote(selfPath()) + " --gtest_filter=-*")
        .out;
  }

  TempDir dir_;
  std::string keystore_;
  std::unique_ptr<RobodiffdProcess> server_;
};

TEST_F(Ownership, OnlyTheOwnerOrAnOperatorActsOnAJobOrAFunction) {
  const std::string spec = (dir_ / "rnea.json").string();
  std::ofstream(spec) << R"({"function": "rnea", "outputs": [{"kind": "value"}]})";
  ProcessResult r = as("alice", "eval --urdf " + shellQuote((sourceDir() / "examples/robots/arm7.urdf").string()) +
                                    " --spec " + shellQuote(spec) + " --random-state 1");
  ASSERT_EQ(r.exit_code, 0) << r.err << server_->log();
  const std::string function_id = json::parse(r.out).at("function_id");

  // A job: a one-knot trajectory of arm7.
  const std::string data = (dir_ / "one.csv").string();
  std::ofstream(data) << "t,q_0,q_1,q_2,q_3,q_4,q_5,q_6,v_0,v_1,v_2,v_3,v_4,v_5,v_6,a_0,a_1,a_2,a_3,a_4,"
                                          "a_5,a_6\n0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n";
  const json params = {{"urdf", (sourceDir() / "examples/robots/arm7.urdf").string()},
                       {"spec_json", json::parse(R"({"function": "rnea", "outputs": [{"kind": "value"}]})")},
                       {"data", data},
                       {"backend", "interpreted"}};
  r = as("alice", "job submit trajectory --params-json " + shellQuote(params.dump()));
  ASSERT_EQ(r.exit_code, 0) << r.err << server_->log();
  std::string job_id = r.out;
  while (!job_id.empty() && (job_id.back() == '\n' || job_id.back() == ' ')) job_id.pop_back();
  ASSERT_EQ(job_id.rfind("job-", 0), 0u) << r.out;

  // alice sees both.
  EXPECT_EQ(as("alice", "job status " + job_id).exit_code, 0);
  r = as("alice", "functions --json");
  EXPECT_NE(r.out.find(function_id), std::string::npos) << r.out << r.err;

  // bob: refused, listings without them, and nothing names alice.
  for (const std::string& command : {"job status " + job_id, "job result " + job_id, "job cancel " + job_id}) {
    r = as("bob", command);
    EXPECT_EQ(r.exit_code, 1) << command << ": " << r.out << r.err;
    EXPECT_NE(r.err.find("PERMISSION_DENIED"), std::string::npos) << command << ": " << r.err;
    EXPECT_NE(r.err.find("belongs to another caller"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("alice"), std::string::npos) << r.err;
  }
  r = as("bob", "job status --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find(job_id), std::string::npos) << r.out;
  r = as("bob", "functions --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find(function_id), std::string::npos) << r.out;
  const std::string refused = releaseAs("bob", function_id);
  EXPECT_EQ(refused.rfind("PERMISSION_DENIED", 0), 0u) << refused << server_->log();

  // ops: sees and acts on everything.
  EXPECT_EQ(as("ops", "job status " + job_id).exit_code, 0);
  r = as("ops", "job status --json");
  EXPECT_NE(r.out.find(job_id), std::string::npos) << r.out << r.err;
  r = as("ops", "functions --json");
  EXPECT_NE(r.out.find(function_id), std::string::npos) << r.out << r.err;
  EXPECT_EQ(as("ops", "job cancel " + job_id).exit_code, 0);
  const std::string released = releaseAs("ops", function_id);
  EXPECT_EQ(released.rfind("OK 0", 0), 0u) << released << server_->log();

  // The server logged who did what.
  EXPECT_NE(server_->log().find("\"caller\":\"dds:alice\""), std::string::npos);
  EXPECT_NE(server_->log().find("\"release_refused\""), std::string::npos);
}

}  // namespace
}  // namespace robodiff::testing
