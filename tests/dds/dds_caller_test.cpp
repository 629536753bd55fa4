// Who calls over DDS: the caller partition of a request's publication (dds_partitions.hpp),
// with real participants on loopback and a real keystore (initKeystore / addIdentity):
// Cyclone 0.10 matches the server's wildcard partitions with a client's own partition; the
// server reads it as "dds:<identity>" (an operator for robodiff.operator.<name>); a client
// whose permissions grant robodiff.caller.alice cannot write in another caller's partition,
// neither by creating the writer (its own plugin refuses) nor by moving it afterwards
// (Cyclone 0.10 does not change a writer's partitions); on open DDS the partition is only
// claimed ("user:<name>", never an operator).

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "dds_secure_env.hpp"
#include "robodiff/schema/dds_codec.hpp"
#include "robodiff/schema/dds_partitions.hpp"

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using client::DdsConnection;
using client::DdsConnectionOptions;
using client::IdentityRole;
using dds_codec::DdsEndpoints;
using dds_codec::DdsSecurity;
using testing::DdsChild;
namespace fs = std::filesystem;


class DdsCallerTest : public testing::DdsTest {
 protected:
  static void SetUpTestSuite() {
    testing::DdsTest::SetUpTestSuite();
    keys_ = new testing::TestKeystore({{"alice", IdentityRole::Client}, {"ops", IdentityRole::Operator}});
  }
  static void TearDownTestSuite() {
    delete keys_;
    keys_ = nullptr;
  }
  DdsConnectionOptions options(const DdsSecurity& security, std::chrono::milliseconds timeout) const {
    DdsConnectionOptions o;
    o.domain_id = domain_;
    o.security = security;
    o.connection.default_timeout = timeout;
    o.match_timeout = timeout;
    return o;
  }
  // Who the server says called.
  static std::string whoCalls(DdsConnection& client) {
    rpc::LoadModelReply reply;
    const Status s = client.loadModel({"<robot/>", false, ""}, reply);
    return s.ok() ? reply.model_id : "error: " + s.message;
  }
  // The request writer of `endpoints` is matched with a server reader within `timeout`.
  static bool writerMatched(const DdsEndpoints& endpoints, std::chrono::milliseconds timeout) {
    return testing::eventually(
        [&] {
          dds_publication_matched_status_t status{};
          dds_get_publication_matched_status(endpoints.writer(), &status);
          return status.current_count > 0;
        },
        timeout);
  }

  // Who the server says called, for a LoadModel written straight on `endpoints`' writer
  // (resent every 250 ms until answered: the server may not see the writer yet).
  static std::string rawWhoCalls(const DdsEndpoints& endpoints, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      dds_codec::WireRequest request;
      rpc::RequestHeader header;
      header.client_id = "raw-caller-test";
      header.correlation_id = 1;
      dds_codec::toWire(header, request->header);
      request->body._d = robodiff_wire_METHOD_LOAD_MODEL;
      dds_codec::toWire(rpc::LoadModelRequest{"<robot/>", false, ""}, request->body._u.load_model);
      if (dds_write(endpoints.writer(), &request.get()) != DDS_RETCODE_OK) return "write failed";
      const auto until = std::chrono::steady_clock::now() + 250ms;
      while (std::chrono::steady_clock::now() < until) {
        dds_codec::WireReply reply;
        void* samples[1] = {&reply.get()};
        dds_sample_info_t info;
        if (dds_take(endpoints.reader(), samples, &info, 1, 1) > 0 && info.valid_data &&
            reply->body._d == robodiff_wire_METHOD_LOAD_MODEL && reply->body._u.load_model.model_id)
          return reply->body._u.load_model.model_id;
        std::this_thread::sleep_for(5ms);
      }
    }
    return "no reply";
  }

  static inline testing::TestKeystore* keys_ = nullptr;
  const std::uint32_t domain_ = testing::freshSecureDomain();
};

TEST_F(DdsCallerTest, KeystoreGrantsEachIdentityItsOwnPartition) {
  const auto alice = dds_codec::keystoreIdentity(keys_->path, "alice");
  EXPECT_EQ(dds_codec::permittedCallerPartition(alice.permissions), "robodiff.caller.alice");
  const auto ops = dds_codec::keystoreIdentity(keys_->path, "ops");
  EXPECT_EQ(dds_codec::permittedCallerPartition(ops.permissions), "robodiff.operator.ops");
  const auto server = dds_codec::keystoreIdentity(keys_->path, "robodiffd");
  EXPECT_THROW(dds_codec::permittedCallerPartition(server.permissions), std::invalid_argument);
  std::stringstream xml;
  xml << std::ifstream(keys_->path / "identities" / "robodiffd" / "permissions.xml").rdbuf();
  EXPECT_NE(xml.str().find("<partition>robodiff.caller.*</partition><partition>robodiff.operator.*</partition>"),
            std::string::npos)
      << xml.str();
}

TEST_F(DdsCallerTest, ServerReadsTheAuthenticatedIdentityFromTheWildcardPartition) {
  DdsChild server("server", domain_, keys_->spec("robodiffd"));
  DdsConnection alice(options(dds_codec::keystoreIdentity(keys_->path, "alice"), 15s));
  EXPECT_EQ(whoCalls(alice), "dds:alice+authenticated");
}

TEST_F(DdsCallerTest, OperatorIdentityIsAnOperator) {
  DdsChild server("server", domain_, keys_->spec("robodiffd"));
  DdsConnection ops(options(dds_codec::keystoreIdentity(keys_->path, "ops"), 15s));
  EXPECT_EQ(whoCalls(ops), "dds:ops+operator+authenticated");
}

TEST_F(DdsCallerTest, WriterInAnotherCallersPartitionIsNotCreated) {
  const DdsSecurity alice = keys_->security("alice");
  DdsEndpoints endpoints(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms, alice);
  ASSERT_GT(testing::rawEndpoint(endpoints, false, {"robodiff.caller.alice"}), 0);  // her own: granted
  for (const char* forged : {"robodiff.caller.bob", "robodiff.operator.alice", "robodiff.caller.*"})
    EXPECT_LT(testing::rawEndpoint(endpoints, false, {forged}), 0) << "alice created a request writer in " << forged;
  EXPECT_LT(testing::rawEndpoint(endpoints, false, {}), 0) << "alice created a request writer in no partition";
  EXPECT_LT(testing::rawEndpoint(endpoints, false, {"robodiff.caller.alice", "robodiff.caller.bob"}), 0);
  // The transport's own endpoints in a forged partition fail naming it.
  try {
    DdsEndpoints forged(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms, alice,
                        "robodiff.caller.bob");
    ADD_FAILURE() << "alice made endpoints in robodiff.caller.bob";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("in partition robodiff.caller.bob"), std::string::npos) << e.what();
  }
}

TEST_F(DdsCallerTest, MovingAWriterToAnotherPartitionIsNotBelieved) {
  DdsChild server("server", domain_, keys_->spec("robodiffd"));
  const DdsSecurity alice = dds_codec::keystoreIdentity(keys_->path, "alice");
  DdsEndpoints endpoints(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms, alice);
  ASSERT_TRUE(writerMatched(endpoints, 15s));
  // On the writer and on its publisher (where the standard puts PARTITION): Cyclone 0.10
  // accepts the calls, but neither changes what the server reads.
  dds_qos_t* qos = dds_create_qos();
  dds_qset_partition1(qos, "robodiff.caller.bob");
  const dds_return_t on_writer = dds_set_qos(endpoints.writer(), qos);
  EXPECT_NE(dds_set_qos(dds_get_parent(endpoints.writer()), qos), DDS_RETCODE_OK);
  dds_delete_qos(qos);
  (void)on_writer;  // DDS_RETCODE_OK, yet ignored:
  dds_qos_t* now = dds_create_qos();
  ASSERT_EQ(dds_get_qos(endpoints.writer(), now), DDS_RETCODE_OK);
  uint32_t count = 0;
  char** names = nullptr;
  ASSERT_TRUE(dds_qget_partition(now, &count, &names));
  ASSERT_EQ(count, 1u);
  EXPECT_STREQ(names[0], "robodiff.caller.alice");
  dds_free(names[0]);
  dds_free(names);
  dds_delete_qos(now);
  std::this_thread::sleep_for(500ms);  // time for a (wrong) re-announcement to reach the server
  EXPECT_EQ(rawWhoCalls(endpoints, 5s), "dds:alice+authenticated");
}

TEST_F(DdsCallerTest, OpenDdsCallerIsTheClaimedUserAndNeverAnOperator) {
  DdsChild server("server", domain_, "open");
  const std::string user = dds_codec::openCallerPartition().substr(dds_codec::kCallerPartitionPrefix.size());
  DdsConnection client(options({}, 15s));
  EXPECT_EQ(whoCalls(client), "user:" + user);
  // A claimed operator partition makes no operator on open DDS.
  DdsEndpoints claimed(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms, {},
                       "robodiff.operator.root");
  ASSERT_TRUE(writerMatched(claimed, 15s));
  EXPECT_EQ(rawWhoCalls(claimed, 15s), "user:root");
}

}  // namespace
}  // namespace robodiff
