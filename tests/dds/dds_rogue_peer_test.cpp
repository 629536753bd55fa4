// A rogue peer under DDS Security: a participant configures its own plugins, so it can load
// documents of its choosing (an all-allowing permissions document, an opened governance)
// signed by a CA it controls, and its own access-control plugin then lets it do anything.
// robodiffd must still refuse it, because the server's plugins check the peer's certificate
// and permissions against the server's own CA. With real participants on loopback: the
// server and a well-behaved client (alice) are children, the rogue is this process. It
// impersonates alice (request writer and reply reader in her partition, wildcard readers)
// and calls with DdsConnection while alice is served. Each case asserts: its own plugin
// allowed the forbidden readers (the bypass is real), it matched nothing, its call ended
// UNAVAILABLE, it took no reply, the server served only alice's 5 requests (its record),
// and alice's answers were right (the child checks the values).

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <sstream>

#include "dds_secure_env.hpp"
#include "support/process.hpp"

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using client::IdentityRole;
using dds_codec::DdsEndpoints;
using dds_codec::DdsSecurity;
using testing::DdsChild;
using testing::TestKeystore;
namespace fs = std::filesystem;

// What the rogue grants itself: an operator's partition, alice's, every caller's, all.
// (DdsConnection calls in the first one: permittedCallerPartition takes an operator's.)
const char* const kRogueClaims[] = {"robodiff.operator.root", "robodiff.caller.alice", "robodiff.caller.*",
                                    "robodiff.operator.*", "*"};
const char* const kRogueImpostorId = "rogue-impostor";

std::string rogueRead(const fs::path& path) {
  std::stringstream text;
  text << std::ifstream(path).rdbuf();
  return text.str();
}

// Signs `xml` into `<xml without .xml>.p7s` with the CA of `keystore`, the way the keystore
// signs its documents (openssl smime -sign -text).
fs::path rogueSign(const fs::path& keystore, const fs::path& xml) {
  fs::path p7s = xml;
  p7s.replace_extension(".p7s");
  using testing::shellQuote;
  const auto result = testing::runCommand(
      "openssl smime -sign -text -in " + shellQuote(xml.string()) + " -out " + shellQuote(p7s.string()) +
      " -signer " + shellQuote((keystore / "ca.cert.pem").string()) + " -inkey " +
      shellQuote((keystore / "private" / "ca.key.pem").string()));
  if (result.exit_code != 0) throw std::runtime_error("signing " + xml.string() + ": " + result.err);
  return p7s;
}

// A permissions document for `subject`: every topic in every claimed partition, default ALLOW.
std::string rogueGrantEverything(const std::string& subject) {
  std::string partitions;
  for (const char* p : kRogueClaims) partitions += std::string("<partition>") + p + "</partition>";
  const std::string rule = "<topics><topic>*</topic></topics><partitions>" + partitions + "</partitions>";
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds><permissions><grant name="rogue"><subject_name>)" +
         subject + R"(</subject_name>
<validity><not_before>2020-01-01T00:00:00</not_before><not_after>2099-01-01T00:00:00</not_after></validity>
<allow_rule><domains><id_range><min>0</min><max>230</max></id_range></domains>
<publish>)" + rule + "</publish><subscribe>" +
         rule + R"(</subscribe></allow_rule>
<default>ALLOW</default></grant></permissions></dds>
)";
}

// The real governance opened up: unauthenticated participants allowed, no join, read or
// write access control; `unprotected`: also discovery, liveliness and data unencrypted.
std::string rogueOpenGovernance(std::string xml, bool unprotected) {
  using Edit = std::pair<const char*, const char*>;
  std::vector<Edit> edits{{"<allow_unauthenticated_participants>false", "<allow_unauthenticated_participants>true"},
                          {"<enable_join_access_control>true", "<enable_join_access_control>false"},
                          {"<enable_read_access_control>true", "<enable_read_access_control>false"},
                          {"<enable_write_access_control>true", "<enable_write_access_control>false"}};
  if (unprotected)
    edits.insert(edits.end(), {{"<discovery_protection_kind>ENCRYPT", "<discovery_protection_kind>NONE"},
                               {"<liveliness_protection_kind>ENCRYPT", "<liveliness_protection_kind>NONE"},
                               {"<data_protection_kind>ENCRYPT", "<data_protection_kind>NONE"}});
  for (const auto& [from, to] : edits) {
    const auto at = xml.find(from);
    if (at == std::string::npos) throw std::runtime_error(std::string("governance has no ") + from);
    xml.replace(at, std::string_view(from).size(), to);
  }
  return xml;
}

// The real keystore (alice, bob) and the rogue's: its own CA, identity "rogue", governance,
// and in forged/ the documents it signed with its CA.
struct RogueKeystores {
  TestKeystore real{{{"alice", IdentityRole::Client}, {"bob", IdentityRole::Client}}};
  TestKeystore rogue{{{"rogue", IdentityRole::Client}}, "rogue"};
  fs::path forged = rogue.path / "forged";

  RogueKeystores() {
    fs::create_directories(forged);
    write("everything-rogue.xml", rogueGrantEverything(client::identitySubject("rogue", IdentityRole::Client)));
    write("everything-bob.xml", rogueGrantEverything(client::identitySubject("bob", IdentityRole::Client)));
    write("open-governance.xml", rogueOpenGovernance(rogueRead(real.path / "governance.xml"), false));
    write("unprotected-governance.xml", rogueOpenGovernance(rogueRead(real.path / "governance.xml"), true));
    write("bob-permissions.xml", rogueRead(real.path / "identities" / "bob" / "permissions.xml"));
  }
  void write(const char* name, const std::string& xml) {
    std::ofstream(forged / name) << xml;
    rogueSign(rogue.path, forged / name);
  }
  // An identity's files: `ca` verifies peers' certificates; `signer` its own documents.
  static DdsSecurity files(const fs::path& ca, const fs::path& identity, const fs::path& signer,
                           const fs::path& governance, const fs::path& permissions) {
    return {ca / "ca.cert.pem", identity / "cert.pem", identity / "key.pem", signer / "ca.cert.pem", governance,
            permissions};
  }
  fs::path realIdentity(const char* name) const { return real.path / "identities" / name; }
};

class DdsRoguePeerTest : public testing::DdsTest {
 protected:
  static void SetUpTestSuite() {
    testing::DdsTest::SetUpTestSuite();
    keys_ = new RogueKeystores();
  }
  static void TearDownTestSuite() {
    delete keys_;
    keys_ = nullptr;
  }

  // alice (a child) is served correctly while `rogue` (this process) impersonates her,
  // listens on every reply partition and calls; the rogue gets nothing, the server never
  // sees its requests.
  void expectRefusedWhileAliceIsServed(const DdsSecurity& rogue) {
    DdsChild server("server", domain_, keys_->real.spec("robodiffd"), served_.string());
    DdsEndpoints impostor(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms, rogue,
                          "robodiff.caller.alice");
    std::vector<dds_entity_t> readers{impostor.reader()};
    for (const char* partition : {"robodiff.caller.*", "*"}) {
      readers.push_back(testing::rawEndpoint(impostor, true, {partition}));
      ASSERT_GT(readers.back(), 0) << "the rogue's own plugin refused a reply reader in " << partition;
    }
    client::DdsConnection caller(callerOptions(rogue));

    DdsChild alice("client", domain_, keys_->real.spec("alice"));
    std::atomic<bool> stop{false};
    std::thread impersonate([&] {
      for (std::uint64_t n = 1; !stop; ++n, std::this_thread::sleep_for(50ms)) writeAsAlice(impostor, n);
    });
    rpc::LoadModelReply reply;
    const Status call = caller.loadModel({"<robot/>", false, ""}, reply);
    const int alice_status = alice.wait(30s);
    stop = true;
    impersonate.join();

    EXPECT_EQ(alice_status, 0) << "alice was not served correctly (3: a wrong or failed answer)";
    EXPECT_EQ(call.code, StatusCode::Unavailable) << call.message << " " << reply.model_id;
    for (const dds_entity_t reader : readers) {
      EXPECT_EQ(takeAll(reader), 0) << "the rogue received replies";
      dds_subscription_matched_status_t matched{};
      dds_get_subscription_matched_status(reader, &matched);
      EXPECT_EQ(matched.total_count, 0u) << "a rogue reply reader matched the server";
    }
    dds_publication_matched_status_t published{};
    dds_get_publication_matched_status(impostor.writer(), &published);
    EXPECT_EQ(published.total_count, 0u) << "the rogue's request writer matched the server";
    expectServedOnlyAlice(caller.clientId());
  }

  // The server's record: alice's kDdsChildCalls LoadModels, read as alice, nothing else.
  void expectServedOnlyAlice(const std::string& rogue_client) const {
    const std::string record = rogueRead(served_);
    std::istringstream lines(record);
    std::string client_id, caller;
    int calls = 0;
    while (lines >> client_id >> caller) {
      ++calls;
      EXPECT_EQ(caller, "dds:alice+authenticated") << record;
      EXPECT_NE(client_id, kRogueImpostorId) << "the server served the impostor";
      EXPECT_NE(client_id, rogue_client) << "the server served the rogue's call";
    }
    EXPECT_EQ(calls, testing::kDdsChildCalls) << record;
  }

  // A LoadModel from kRogueImpostorId on the impostor's writer (in alice's partition).
  static void writeAsAlice(const DdsEndpoints& impostor, std::uint64_t n) {
    rpc::RequestHeader forged;
    forged.client_id = kRogueImpostorId;
    forged.correlation_id = n;
    dds_codec::WireRequest wire;
    dds_codec::toWire(forged, wire->header);
    wire->body._d = robodiff_wire_METHOD_LOAD_MODEL;
    dds_codec::toWire(rpc::LoadModelRequest{"<robot/>", false, ""}, wire->body._u.load_model);
    dds_write(impostor.writer(), &wire.get());
  }

  // How many samples `reader` held (taken).
  static int takeAll(dds_entity_t reader) {
    int count = 0;
    void* samples[8] = {};
    dds_sample_info_t infos[8];
    for (dds_return_t n; (n = dds_take(reader, samples, infos, 8, 8)) > 0;) {
      count += n;
      dds_return_loan(reader, samples, n);
    }
    return count;
  }

  client::DdsConnectionOptions callerOptions(const DdsSecurity& security) const {
    client::DdsConnectionOptions o;
    o.domain_id = domain_;
    o.security = security;
    o.connection.default_timeout = 2s;
    o.match_timeout = 2s;
    return o;
  }

  static inline RogueKeystores* keys_ = nullptr;
  const std::uint32_t domain_ = testing::freshSecureDomain();
  testing::TempDir served_dir_;
  const fs::path served_ = served_dir_ / "served";  // the server's record (CallerEchoService)
};

TEST_F(DdsRoguePeerTest, OwnCaWithEverythingAllowedIsRefused) {
  const fs::path& ca = keys_->rogue.path;
  expectRefusedWhileAliceIsServed(RogueKeystores::files(ca, ca / "identities" / "rogue", ca, ca / "governance.p7s",
                                                        keys_->forged / "everything-rogue.p7s"));
}

TEST_F(DdsRoguePeerTest, ValidCertificateWithPermissionsOfARogueCaIsRefused) {
  // bob's real certificate; its plugin trusts the rogue CA for governance and permissions.
  const fs::path& rogue_ca = keys_->rogue.path;
  expectRefusedWhileAliceIsServed(RogueKeystores::files(keys_->real.path, keys_->realIdentity("bob"), rogue_ca,
                                                        rogue_ca / "governance.p7s",
                                                        keys_->forged / "everything-bob.p7s"));
}

TEST_F(DdsRoguePeerTest, ValidCertificateWithAnothersPermissionsIsRefused) {
  // bob's certificate, alice's genuine permissions (subject CN=alice): Cyclone's own plugin
  // refuses to create the participant (the grant's subject is not the certificate's), so
  // it never reaches the server; alice is served meanwhile.
  const fs::path& real = keys_->real.path;
  const DdsSecurity mismatched = RogueKeystores::files(real, keys_->realIdentity("bob"), real, real / "governance.p7s",
                                                       keys_->realIdentity("alice") / "permissions.p7s");
  DdsChild server("server", domain_, keys_->real.spec("robodiffd"), served_.string());
  DdsChild alice("client", domain_, keys_->real.spec("alice"));
  try {
    DdsEndpoints impostor(domain_, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client, 1s, 0ms, mismatched,
                          "robodiff.caller.alice");
    ADD_FAILURE() << "a participant with bob's certificate and alice's permissions was created";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("dds_create_participant failed"), std::string::npos) << e.what();
  }
  EXPECT_THROW(client::DdsConnection{callerOptions(mismatched)}, std::runtime_error);
  EXPECT_EQ(alice.wait(30s), 0) << "alice was not served correctly (3: a wrong or failed answer)";
  expectServedOnlyAlice("");
}

TEST_F(DdsRoguePeerTest, GovernanceOpenedByARogueCaIsRefused) {
  // bob's certificate and permissions (re-signed), the governance opened and re-signed; its
  // protection kinds kept, so in discovery it looks like any secure participant.
  expectRefusedWhileAliceIsServed(RogueKeystores::files(keys_->real.path, keys_->realIdentity("bob"),
                                                        keys_->rogue.path, keys_->forged / "open-governance.p7s",
                                                        keys_->forged / "bob-permissions.p7s"));
}

TEST_F(DdsRoguePeerTest, UnprotectedGovernanceOfARogueCaIsRefused) {
  // As above, with discovery, liveliness and data unencrypted too.
  expectRefusedWhileAliceIsServed(RogueKeystores::files(keys_->real.path, keys_->realIdentity("bob"),
                                                        keys_->rogue.path, keys_->forged / "unprotected-governance.p7s",
                                                        keys_->forged / "bob-permissions.p7s"));
}

}  // namespace
}  // namespace robodiff
