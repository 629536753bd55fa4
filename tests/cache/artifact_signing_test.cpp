// Ed25519 keys and signatures for cache artifacts, checked against the openssl command
// line as an independent implementation: its signatures verify here, ours verify there,
// the key id is the SHA-256 of the raw key it prints. Key files: modes, refusals.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/model/canonical.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::cache {
namespace {

namespace fs = std::filesystem;
using testing::runCommand;
using testing::shellQuote;
using testing::TempDir;

unsigned signingModeOf(const fs::path& p) {
  struct stat st {};
  EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
  return st.st_mode & 07777u;
}

// Runs a shell command that must succeed; its stdout.
std::string signingShell(const std::string& command) {
  const testing::ProcessResult r = runCommand("(" + command + ")");  // a pipeline's first stdin is kept
  EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.err;
  return r.out;
}

TEST(ArtifactSigning, SignaturesVerifyOnlyForTheirMessageAndKey) {
  const SigningKey key = SigningKey::generate();
  const SigningKey other = SigningKey::generate();
  const std::string message = R"({"key":"abc","files":[]})";
  const std::string signature = key.sign(message);
  ASSERT_EQ(signature.size(), 64u);
  EXPECT_TRUE(key.publicKey().verify(message, signature));
  EXPECT_FALSE(other.publicKey().verify(message, signature)) << "a wrong key accepted the signature";
  EXPECT_FALSE(key.publicKey().verify(message + " ", signature));
  std::string flipped = signature;
  flipped[10] = static_cast<char>(flipped[10] ^ 0x01);
  EXPECT_FALSE(key.publicKey().verify(message, flipped));
  EXPECT_FALSE(key.publicKey().verify(message, signature.substr(0, 63)));
  EXPECT_NE(key.keyId(), other.keyId());
  EXPECT_EQ(key.keyId().size(), 16u);
}

TEST(ArtifactSigning, KeyFilesHaveTheirModesAndAreNeverOverwritten) {
  TempDir tmp;
  const SigningKey key = SigningKey::generate();
  key.writePair(tmp / "keys", "build-host");
  EXPECT_EQ(signingModeOf(tmp / "keys" / "build-host.key"), 0600u);
  EXPECT_EQ(signingModeOf(tmp / "keys" / "build-host.pub"), 0644u);
  EXPECT_EQ(signingModeOf(tmp / "keys"), 0700u);

  const SigningKey loaded = SigningKey::load(tmp / "keys" / "build-host.key");
  EXPECT_EQ(loaded.keyId(), key.keyId());
  EXPECT_EQ(PublicKey::load(tmp / "keys" / "build-host.pub").keyId(), key.keyId());
  EXPECT_TRUE(key.publicKey().verify("m", loaded.sign("m")));

  const std::string before = testing::readFile(tmp / "keys" / "build-host.key");
  try {
    SigningKey::generate().writePair(tmp / "keys", "build-host");
    ADD_FAILURE() << "an existing key was overwritten";
  } catch (const SigningError& e) {
    EXPECT_NE(std::string(e.what()).find("refusing to overwrite"), std::string::npos) << e.what();
  }
  EXPECT_EQ(testing::readFile(tmp / "keys" / "build-host.key"), before);
  EXPECT_THROW(key.writePair(tmp / "keys", "../escape"), SigningError);
  EXPECT_FALSE(fs::exists(tmp / "escape.key"));
}

TEST(ArtifactSigning, APrivateKeyReadableByOthersIsRefused) {
  TempDir tmp;
  SigningKey::generate().writePair(tmp.path(), "k");
  const fs::path file = tmp / "k.key";
  for (const unsigned mode : {0644u, 0640u, 0604u}) {
    ::chmod(file.c_str(), mode);
    try {
      SigningKey::load(file);
      ADD_FAILURE() << "a private key with mode " << std::oct << mode << " was used";
    } catch (const SigningError& e) {
      EXPECT_NE(std::string(e.what()).find("has mode 0" + [&] {
        char m[8];
        std::snprintf(m, sizeof m, "%o", mode);
        return std::string(m);
      }()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("chmod 600"), std::string::npos) << e.what();
    }
  }
  ::chmod(file.c_str(), 0400);
  EXPECT_NO_THROW(SigningKey::load(file));
}

TEST(ArtifactSigning, MalformedAndForeignKeyFilesAreRefusedByName) {
  TempDir tmp;
  const fs::path garbage = tmp.file("garbage.pub", "not a key\n");
  try {
    PublicKey::load(garbage);
    ADD_FAILURE() << "garbage accepted as a public key";
  } catch (const SigningError& e) {
    EXPECT_NE(std::string(e.what()).find(garbage.string()), std::string::npos) << e.what();
  }
  // An EC key is a valid PEM key, but not Ed25519.
  const fs::path ec = tmp / "ec.pub";
  signingShell("openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 2>/dev/null | openssl pkey -pubout -out " +
               shellQuote(ec.string()));
  try {
    PublicKey::load(ec);
    ADD_FAILURE() << "an EC key accepted";
  } catch (const SigningError& e) {
    EXPECT_NE(std::string(e.what()).find("Ed25519"), std::string::npos) << e.what();
  }
  EXPECT_THROW(PublicKey::load(tmp / "missing.pub"), SigningError);
}

// The openssl command line is the reference implementation of Ed25519 and of the key id.
TEST(ArtifactSigning, AgreesWithTheOpensslCommandLine) {
  TempDir tmp;
  const SigningKey key = SigningKey::generate();
  key.writePair(tmp.path(), "ours");
  const fs::path message = tmp.file("message", "robodiff manifest bytes\n");

  // Key id: SHA-256 of the raw 32-byte key (the last 32 bytes of its DER form).
  const std::string id = signingShell("openssl pkey -pubin -in " + shellQuote((tmp / "ours.pub").string()) +
                                      " -outform DER | tail -c 32 | sha256sum | cut -c1-16");
  EXPECT_EQ(id, key.keyId() + "\n");

  // Our signature verifies with openssl.
  std::ofstream(tmp / "ours.sig", std::ios::binary) << key.sign(testing::readFile(message));
  signingShell("openssl pkeyutl -verify -pubin -inkey " + shellQuote((tmp / "ours.pub").string()) + " -rawin -in " +
               shellQuote(message.string()) + " -sigfile " + shellQuote((tmp / "ours.sig").string()));

  // openssl's key and signature work here.
  const fs::path theirs = tmp / "theirs.key";
  signingShell("openssl genpkey -algorithm ed25519 -out " + shellQuote(theirs.string()) + " && chmod 600 " +
               shellQuote(theirs.string()));
  signingShell("openssl pkeyutl -sign -inkey " + shellQuote(theirs.string()) + " -rawin -in " +
               shellQuote(message.string()) + " -out " + shellQuote((tmp / "theirs.sig").string()));
  const SigningKey loaded = SigningKey::load(theirs);
  EXPECT_TRUE(loaded.publicKey().verify(testing::readFile(message), testing::readFile(tmp / "theirs.sig")));
  EXPECT_EQ(loaded.sign(testing::readFile(message)), testing::readFile(tmp / "theirs.sig"))
      << "Ed25519 signatures are deterministic";
}

TEST(ArtifactSigning, TrustedKeysComeFromFilesAndDirectories) {
  TempDir tmp;
  const SigningKey a = SigningKey::generate(), b = SigningKey::generate(), c = SigningKey::generate();
  a.writePair(tmp / "fleet", "a");
  b.writePair(tmp / "fleet", "b");
  c.writePair(tmp / "other", "c");
  const TrustedKeys trusted = TrustedKeys::load({tmp / "fleet", tmp / "other" / "c.pub"});
  EXPECT_EQ(trusted.size(), 3u);
  ASSERT_NE(trusted.find(a.keyId()), nullptr);
  EXPECT_TRUE(trusted.find(a.keyId())->verify("x", a.sign("x")));
  EXPECT_NE(trusted.find(c.keyId()), nullptr);
  EXPECT_EQ(trusted.find(SigningKey::generate().keyId()), nullptr);
  // The private key files in the directory are not read as trusted keys.
  EXPECT_EQ(TrustedKeys::load({tmp / "fleet"}).size(), 2u);
  EXPECT_THROW(TrustedKeys::load({tmp / "nowhere"}), SigningError);
  fs::create_directory(tmp / "empty");
  EXPECT_THROW(TrustedKeys::load({tmp / "empty"}), SigningError);
}

TEST(ArtifactSigning, HexRoundTripsAndRejectsBadDigits) {
  const std::string bytes("\x00\x7f\x80\xff", 4);
  EXPECT_EQ(toHex(bytes), "007f80ff");
  EXPECT_EQ(fromHex("007f80ff"), bytes);
  EXPECT_THROW(fromHex("0"), std::invalid_argument);
  EXPECT_THROW(fromHex("0g"), std::invalid_argument);
}

}  // namespace
}  // namespace robodiff::cache
