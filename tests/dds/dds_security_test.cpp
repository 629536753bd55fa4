// DDS Security on the DDS transport, with real participants on loopback and a real keystore
// made by initKeystore/addIdentity (what `robodiff security` runs): an authenticated client
// is served; a participant without credentials can neither call nor listen; an identity of
// another CA and a tampered permissions document are refused.

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "dds_secure_env.hpp"

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using client::DdsConnection;
using client::DdsConnectionOptions;
using client::IdentityRole;
using dds_codec::DdsSecurity;
using testing::DdsChild;
using testing::TestKeystore;

namespace fs = std::filesystem;

// Two keystores (two CAs) for the whole suite: making keys takes a few openssl runs.
struct Keystores {
  TestKeystore ours{{{"alice", IdentityRole::Client}}};
  TestKeystore theirs{{{"mallory", IdentityRole::Client}}, "other"};
};

class DdsSecurityTest : public testing::DdsTest {
 protected:
  static void SetUpTestSuite() {
    testing::DdsTest::SetUpTestSuite();
    keys_ = new Keystores();
  }
  static void TearDownTestSuite() {
    delete keys_;
    keys_ = nullptr;
  }

  std::unique_ptr<DdsChild> startSecureServer() {
    return std::make_unique<DdsChild>("server", domain_, keys_->ours.spec("robodiffd"));
  }
  DdsConnectionOptions clientOptions(const DdsSecurity& security, std::chrono::milliseconds timeout) const {
    DdsConnectionOptions o;
    o.domain_id = domain_;
    o.security = security;
    o.connection.default_timeout = timeout;
    o.match_timeout = timeout;
    return o;
  }
  // A LoadModel, answered with who called (CallerEchoService).
  static Status load(DdsConnection& client, rpc::LoadModelReply& reply) {
    return client.loadModel({"<robot/>", false, ""}, reply);
  }

  static inline Keystores* keys_ = nullptr;
  const std::uint32_t domain_ = testing::freshSecureDomain();
};

TEST_F(DdsSecurityTest, AuthenticatedClientIsServed) {
  auto server = startSecureServer();
  DdsConnection alice(clientOptions(keys_->ours.security("alice"), 15s));
  rpc::LoadModelReply reply;
  const Status s = load(alice, reply);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(reply.model_id, "dds:alice+authenticated");
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
  DdsChild alice("client", domain_, keys_->ours.spec("alice"));
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
  DdsConnection mallory(clientOptions(keys_->theirs.security("mallory"), 3s));
  rpc::LoadModelReply reply;
  const Status s = load(mallory, reply);
  EXPECT_EQ(s.code, StatusCode::Unavailable) << s.message;
}

TEST_F(DdsSecurityTest, TamperedPermissionsAreRefused) {
  // alice's identity, with her signed permissions edited to let her read requests too.
  const fs::path eve = keys_->ours.path / "identities" / "eve";
  fs::create_directories(eve);
  for (const char* f : {"cert.pem", "key.pem", "permissions.p7s"})
    fs::copy_file(keys_->ours.path / "identities" / "alice" / f, eve / f, fs::copy_options::overwrite_existing);
  std::stringstream text;
  text << std::ifstream(eve / "permissions.p7s").rdbuf();
  std::string p7s = text.str();
  const std::string granted = "<topic>robodiff_reply</topic>";
  const auto at = p7s.find(granted);
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, granted.size(), "<topic>robodiff_*</topic>");
  std::ofstream(eve / "permissions.p7s", std::ios::trunc) << p7s;

  auto server = startSecureServer();
  const DdsSecurity security = dds_codec::keystoreIdentity(keys_->ours.path, "eve");
  try {
    DdsConnection tampered(clientOptions(security, 3s));
    ADD_FAILURE() << "a participant with tampered permissions was created";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("with DDS security (identity eve"), std::string::npos) << e.what();
  }
}

TEST_F(DdsSecurityTest, KeystoreNamesRolesAndRefusesDuplicates) {
  client::addIdentity(keys_->ours.path, "ops", IdentityRole::Operator);
  std::stringstream permissions;
  permissions << std::ifstream(keys_->ours.path / "identities" / "ops" / "permissions.xml").rdbuf();
  EXPECT_NE(permissions.str().find("<subject_name>CN=ops,OU=operators,O=robodiff</subject_name>"), std::string::npos);
  std::stringstream server;
  server << std::ifstream(keys_->ours.path / "identities" / "robodiffd" / "permissions.xml").rdbuf();
  EXPECT_NE(server.str().find("<publish><topics><topic>robodiff_reply</topic>"), std::string::npos) << server.str();
  EXPECT_THROW(client::addIdentity(keys_->ours.path, "alice", IdentityRole::Client), std::invalid_argument);
  EXPECT_THROW(client::addIdentity(keys_->ours.path, "../x", IdentityRole::Client), std::invalid_argument);
  EXPECT_THROW(client::initKeystore(keys_->ours.path), std::runtime_error);
  EXPECT_EQ(fs::status(keys_->ours.path / "private" / "ca.key.pem").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
}

TEST_F(DdsSecurityTest, MissingKeystoreFileIsNamed) {
  try {
    dds_codec::keystoreIdentity(keys_->ours.path, "nobody");
    FAIL() << "no error for a missing identity";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("identities/nobody/cert.pem"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace robodiff
