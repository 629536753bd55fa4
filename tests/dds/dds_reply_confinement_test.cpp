// Replies confined to their caller (deploy/security.md): robodiffd answers each request in
// the caller partition of its publication, and under DDS Security an identity may read the
// reply topic only in its own partition. With real participants on loopback and a keystore
// made by the project's code: bob cannot make a reply reader in alice's partition (his own
// access-control plugin refuses it), nor in a wildcard or the default partition, and the
// reader he may have, in his own partition, receives none of alice's replies while alice
// (another process) is served. Server side: a request from a publication in no caller
// partition (an empty name, several partitions) is not served, and the server says so in
// its log; it is tested on open DDS, where such a writer can be made at all (under DDS
// Security the writer's own plugin refuses it: dds_caller_test).

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "dds_secure_env.hpp"
#include "robodiff/schema/dds_partitions.hpp"

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using client::DdsConnection;
using client::DdsConnectionOptions;
using client::IdentityRole;
using dds_codec::DdsEndpoints;
using testing::DdsChild;
using testing::rawEndpoint;

// A LoadModel written straight on `endpoints`' request writer as `client_id`.
dds_return_t writeLoadModel(const DdsEndpoints& endpoints, dds_entity_t writer, const std::string& client_id) {
  dds_codec::WireRequest request;
  rpc::RequestHeader header;
  header.client_id = client_id;
  header.correlation_id = 1;
  dds_codec::toWire(header, request->header);
  request->body._d = robodiff_wire_METHOD_LOAD_MODEL;
  dds_codec::toWire(rpc::LoadModelRequest{"<robot/>", false, ""}, request->body._u.load_model);
  return dds_write(writer > 0 ? writer : endpoints.writer(), &request.get());
}

// The client ids of the reply samples `reader` holds (taken).
std::vector<std::string> takeReplyClients(dds_entity_t reader) {
  std::vector<std::string> clients;
  for (;;) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info;
    if (dds_take(reader, samples, &info, 1, 1) <= 0) return clients;
    const auto* reply = static_cast<const robodiff_wire_Reply*>(samples[0]);
    if (info.valid_data) clients.emplace_back(reply->header.client_id ? reply->header.client_id : "");
    dds_return_loan(reader, samples, 1);
  }
}

class DdsReplyConfinementTest : public testing::DdsTest {
 protected:
  static void SetUpTestSuite() {
    testing::DdsTest::SetUpTestSuite();
    keys_ = new testing::TestKeystore({{"alice", IdentityRole::Client}, {"bob", IdentityRole::Client}});
  }
  static void TearDownTestSuite() {
    delete keys_;
    keys_ = nullptr;
  }
  DdsConnectionOptions options(const dds_codec::DdsSecurity& security) const {
    DdsConnectionOptions o;
    o.domain_id = domain_;
    o.security = security;
    o.connection.default_timeout = 15s;
    o.match_timeout = 15s;
    return o;
  }

  static inline testing::TestKeystore* keys_ = nullptr;
  const std::uint32_t domain_ = testing::freshSecureDomain();
};

TEST_F(DdsReplyConfinementTest, KeystoreGrantsRepliesOnlyInTheCallersPartition) {
  std::stringstream client, server;
  client << std::ifstream(keys_->path / "identities" / "bob" / "permissions.xml").rdbuf();
  EXPECT_NE(client.str().find("<subscribe><topics><topic>robodiff_reply</topic></topics><partitions><partition>"
                              "robodiff.caller.bob</partition></partitions></subscribe>"),
            std::string::npos)
      << client.str();
  server << std::ifstream(keys_->path / "identities" / "robodiffd" / "permissions.xml").rdbuf();
  EXPECT_NE(server.str().find("<publish><topics><topic>robodiff_reply</topic></topics><partitions><partition>"
                              "robodiff.caller.*</partition><partition>robodiff.operator.*</partition>"),
            std::string::npos)
      << server.str();
}

TEST(DdsReplyPartition, OnlyAPlainCallerNameIsACallerPartition) {
  const auto alice = dds_codec::callerOfPartition("robodiff.caller.alice");
  ASSERT_TRUE(alice);
  EXPECT_EQ(alice->name, "alice");
  EXPECT_FALSE(alice->operator_);
  const auto ops = dds_codec::callerOfPartition("robodiff.operator.ops");
  ASSERT_TRUE(ops);
  EXPECT_TRUE(ops->operator_);
  for (const char* not_a_caller : {"", "robodiff.caller.", "robodiff.operator.", "robodiff.caller.a*", "robodiff.caller.?",
                                   "robodiff.caller.[ab]", "robodiff.caller.a\\b", "robodiff.callers.x", "other"})
    EXPECT_FALSE(dds_codec::callerOfPartition(not_a_caller)) << not_a_caller;
}

TEST_F(DdsReplyConfinementTest, ReplyReaderInAnotherCallersPartitionIsNotCreated) {
  DdsEndpoints bob(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms,
                   keys_->security("bob"));
  EXPECT_GT(rawEndpoint(bob, true, {"robodiff.caller.bob"}), 0);  // his own: granted
  for (const char* other : {"robodiff.caller.alice", "robodiff.operator.alice", "robodiff.caller.*", "*"})
    EXPECT_LT(rawEndpoint(bob, true, {other}), 0) << "bob made a reply reader in " << other;
  EXPECT_LT(rawEndpoint(bob, true, {}), 0) << "bob made a reply reader in the default partition";
  EXPECT_LT(rawEndpoint(bob, true, {"robodiff.caller.bob", "robodiff.caller.alice"}), 0);
}

TEST_F(DdsReplyConfinementTest, AnotherCallerReceivesNoneOfAlicesReplies) {
  DdsChild server("server", domain_, keys_->spec("robodiffd"));
  // bob's transport endpoints (his reply reader, in his partition) and any wildcard reader
  // his plugin would let him make.
  DdsEndpoints bob(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms,
                   keys_->security("bob"));
  std::vector<dds_entity_t> readers{bob.reader()};
  for (const char* pattern : {"robodiff.caller.*", "robodiff.*", "*"})
    if (const dds_entity_t r = rawEndpoint(bob, true, {pattern}); r > 0) readers.push_back(r);
  ASSERT_TRUE(testing::eventually(
      [&] {
        dds_subscription_matched_status_t s{};
        dds_get_subscription_matched_status(bob.reader(), &s);
        return s.current_count > 0;
      },
      20s))
      << "bob's reply reader never matched the server's writer in his partition";

  DdsChild alice("client", domain_, keys_->spec("alice"));
  ASSERT_EQ(alice.wait(60s), 0) << "alice was not served";

  // bob's own call is answered on his reader: the reader works, and sees only bob.
  std::set<std::string> seen;
  const bool answered = testing::eventually(
      [&] {
        writeLoadModel(bob, 0, "bob-raw");
        std::this_thread::sleep_for(100ms);
        for (const dds_entity_t r : readers)
          for (const std::string& c : takeReplyClients(r)) seen.insert(c);
        return seen.count("bob-raw") > 0;
      },
      20s);
  EXPECT_TRUE(answered) << "bob's own request was not answered";
  for (const std::string& c : seen) EXPECT_EQ(c, "bob-raw") << "bob received a reply to " << c;
}

// An open-DDS server in this process, its log in a file.
class DdsUnansweredRequestTest : public testing::DdsTest {
 protected:
  void SetUp() override {
    log_file_ = std::fopen(log_path_.c_str(), "w");
    ASSERT_NE(log_file_, nullptr);
    log_ = std::make_unique<server::Logger>(log_file_, server::LogLevel::Warn);
    server::DdsServerOptions o;
    o.domain_id = domain_;
    server_ = std::make_unique<server::DdsServer>(service_, o, *log_);
    server_->start();
  }
  void TearDown() override {
    server_.reset();
    log_.reset();
    if (log_file_) std::fclose(log_file_);
  }
  std::string log() const {
    std::fflush(log_file_);
    std::stringstream text;
    text << std::ifstream(log_path_).rdbuf();
    return text.str();
  }
  // True when the service saw a LoadModel from `client_id`.
  bool served(const std::string& client_id) const {
    for (const auto& c : service_.loadModelClients())
      if (c == client_id) return true;
    return false;
  }

  const std::uint32_t domain_ = testing::testDomain();
  testing::TempDir dir_;
  const std::filesystem::path log_path_ = dir_ / "robodiffd.log";
  std::FILE* log_file_ = nullptr;
  testing::FakeService service_{"srv-unanswered"};
  std::unique_ptr<server::Logger> log_;
  std::unique_ptr<server::DdsServer> server_;
};

TEST_F(DdsUnansweredRequestTest, RequestFromNoCallerPartitionIsNotServed) {
  // A publication in "robodiff.caller." (no name) matches the server's wildcard reader.
  DdsEndpoints nameless(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms, {},
                        std::string(dds_codec::kCallerPartitionPrefix));
  // A writer in two caller partitions at once.
  const dds_entity_t twice = rawEndpoint(nameless, false, {"robodiff.caller.a", "robodiff.caller.b"});
  ASSERT_GT(twice, 0);
  DdsConnection honest([&] {
    DdsConnectionOptions o;
    o.domain_id = domain_;
    o.match_timeout = 15s;
    return o;
  }());
  rpc::LoadModelReply reply;
  ASSERT_TRUE(honest.loadModel({"<robot/>", false, ""}, reply, client::CallOptions{15s}).ok());
  // Sent until the server has logged both (it may not see the writers at first).
  const bool refused = testing::eventually(
      [&] {
        writeLoadModel(nameless, 0, "nameless");
        writeLoadModel(nameless, twice, "twice");
        std::this_thread::sleep_for(50ms);
        const std::string text = log();
        return text.find("names no caller") != std::string::npos &&
               text.find("is in 2 partitions, not one caller partition") != std::string::npos;
      },
      15s);
  EXPECT_TRUE(refused) << log();
  EXPECT_NE(log().find("\"event\":\"dds_request_not_served\""), std::string::npos) << log();
  EXPECT_FALSE(served("nameless"));
  EXPECT_FALSE(served("twice"));
  EXPECT_TRUE(takeReplyClients(nameless.reader()).empty());
  // The well-behaved client is still served.
  EXPECT_TRUE(honest.loadModel({"<robot/>", false, ""}, reply, client::CallOptions{15s}).ok());
}

}  // namespace
}  // namespace robodiff
