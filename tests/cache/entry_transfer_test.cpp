// One signed entry sent as a manifest plus its payload (its files concatenated in the
// manifest's order) and received through EntryReceiver into another real cache, in chunks
// of any size; and every way what arrives can be wrong (unknown signer, altered signature,
// another key, an altered, truncated or overlong payload, over the limits), each leaving
// the receiving cache without the entry. Artifacts are made-up files: nothing loads them.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "cache/cache_fixtures.hpp"
#include "robodiff/cache/entry_transfer.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::cache {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

constexpr std::int64_t kXferSignedAt = 1700000000;

// A source cache with one entry (library, description, two sources) found by its key
// and its portable key, a trusted signer, and an empty target cache.
struct XferWorld {
  TempDir tmp;
  Cache source = Cache::open(tmp / "source");
  Cache target = Cache::open(tmp / "target");
  SigningKey signer = SigningKey::generate();
  TrustedKeys trusted;
  std::string key = keyOf("xfer");
  std::string portable = sha256Hex("xfer portable");
  std::string library, description = R"({"name":"xfer"})";
  std::string source_b = "double xfer_b(double x) { return 2 * x; }\n", source_a = "double xfer_a(double x);\n";

  XferWorld() {
    trusted.add(signer.publicKey());
    library.resize(10007);
    for (std::size_t i = 0; i < library.size(); ++i) library[i] = static_cast<char>((i * 131 + 17) & 0xff);
    EntryInfo info = infoFor("xfer");
    info.compiler += " target=generic";
    info.portable_key = portable;
    ClaimResult r = source.claim(key, info);
    EXPECT_EQ(r.state, ClaimResult::State::Claimed);
    source.publish(*r.claim, info,
                   {tmp.file("lib.so", library), tmp.file("desc.json", description),
                    {tmp.file("xfer_b.c", source_b), tmp.file("xfer_a.c", source_a)}});
  }

  SignedEntry sign(bool sources) { return signEntry(exportableArtifact(source, key), signer, sources, kXferSignedAt); }

  // The payload as the manifest orders it: files sorted by name.
  std::string expectedPayload(bool sources) const {
    return description + library + (sources ? source_a + source_b : "");
  }

  bool targetHasIt() { return target.entry(key).has_value() || target.findPortable(portable).has_value(); }
};

// The payload read back from `entry` in chunks of `chunk` bytes.
std::string xferPayload(const SignedEntry& entry, std::size_t chunk) {
  std::string payload;
  std::vector<std::uint8_t> buf;
  for (std::uint64_t offset = 0;; offset += buf.size()) {
    entry.readPayload(offset, chunk, buf);
    if (buf.empty()) return payload;
    EXPECT_LE(buf.size(), chunk);
    payload.append(buf.begin(), buf.end());
  }
}

// Feeds `payload` to the receiver in chunks of `chunk` bytes.
void xferAppend(EntryReceiver& receiver, const std::string& payload, std::size_t chunk) {
  for (std::size_t at = 0; at < payload.size(); at += chunk) {
    const std::size_t n = std::min(chunk, payload.size() - at);
    receiver.append(reinterpret_cast<const std::uint8_t*>(payload.data() + at), n);
  }
}

// Runs `f`, expecting TransferRefused whose message contains `words`.
template <typename F>
void xferExpectRefused(F f, const std::string& words) {
  try {
    f();
    ADD_FAILURE() << "not refused; expected: " << words;
  } catch (const TransferRefused& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(EntryTransfer, ThePayloadIsTheFilesInTheManifestsOrder) {
  XferWorld w;
  for (const bool sources : {true, false}) {
    const SignedEntry e = w.sign(sources);
    const std::string expected = w.expectedPayload(sources);
    EXPECT_EQ(e.payloadBytes(), expected.size());
    for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{4096}, expected.size()})
      EXPECT_EQ(xferPayload(e, chunk), expected) << "chunks of " << chunk;
    std::vector<std::uint8_t> buf{1, 2, 3};
    e.readPayload(expected.size(), 10, buf);
    EXPECT_TRUE(buf.empty());
    e.readPayload(expected.size() + 5, 10, buf);
    EXPECT_TRUE(buf.empty());
    // Across the boundary between description.json and library.so.
    e.readPayload(w.description.size() - 2, 4, buf);
    EXPECT_EQ(std::string(buf.begin(), buf.end()), expected.substr(w.description.size() - 2, 4));

    const EntryManifest m = parseManifest(e.manifest);
    EXPECT_EQ(m.key, w.key);
    EXPECT_EQ(m.files.size(), sources ? 4u : 2u);
    EXPECT_EQ(m.signed_at, kXferSignedAt);
    EXPECT_TRUE(w.signer.publicKey().verify(e.manifest, fromHex(e.signature_hex)));
  }
}

TEST(EntryTransfer, ReceivedInAnyChunksItIsFoundByKeyAndPortableKey) {
  for (const bool sources : {true, false}) {
    XferWorld w;
    const SignedEntry e = w.sign(sources);
    const std::string payload = xferPayload(e, 1 << 16);
    for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, payload.size()}) {
      SCOPED_TRACE("sources " + std::to_string(sources) + ", chunks of " + std::to_string(chunk));
      Cache target = Cache::open(w.tmp / ("target-" + std::to_string(sources) + "-" + std::to_string(chunk)));
      EntryReceiver receiver(e.manifest, e.signature_hex, w.trusted, w.key);
      EXPECT_EQ(receiver.payloadBytes(), payload.size());
      EXPECT_EQ(receiver.manifest().key, w.key);
      xferAppend(receiver, payload, chunk);
      EXPECT_TRUE(receiver.complete());
      EXPECT_EQ(receiver.received(), payload.size());
      const ImportResult r = receiver.install(target);
      EXPECT_EQ(r.status, ImportResult::Status::Imported) << r.problem;
      EXPECT_EQ(r.signer, w.signer.keyId());
      EXPECT_EQ(r.function, "xfer");

      const std::optional<Artifact> got = target.find(w.key);
      ASSERT_TRUE(got);
      EXPECT_EQ(testing::readFile(got->library()), w.library);
      EXPECT_EQ(testing::readFile(got->description()), w.description);
      const std::optional<Artifact> by_portable = target.findPortable(w.portable);
      ASSERT_TRUE(by_portable);
      EXPECT_EQ(by_portable->key(), w.key);
      const std::size_t source_files = sources ? 2 : 0;
      std::size_t found_sources = 0;
      std::error_code ec;
      for (fs::directory_iterator it(got->dir() / "src", ec), end; !ec && it != end; it.increment(ec)) ++found_sources;
      EXPECT_EQ(found_sources, source_files);
      EXPECT_TRUE(target.verify().problems.empty());
      // The same entry again: already there, left alone.
      EntryReceiver again(e.manifest, e.signature_hex, w.trusted, "");
      xferAppend(again, payload, payload.size());
      EXPECT_EQ(again.install(target).status, ImportResult::Status::Present);
    }
  }
}

TEST(EntryTransfer, ABadSignatureOrAnotherKeyIsRefusedBeforeAnyByte) {
  XferWorld w;
  const SignedEntry e = w.sign(true);
  const SignedEntry stranger = signEntry(exportableArtifact(w.source, w.key), SigningKey::generate(), true, 1);
  xferExpectRefused([&] { EntryReceiver(stranger.manifest, stranger.signature_hex, w.trusted, w.key); },
                    "unknown key");
  std::string flipped = e.signature_hex;
  flipped[10] = flipped[10] == '0' ? '1' : '0';
  xferExpectRefused([&] { EntryReceiver(e.manifest, flipped, w.trusted, w.key); }, "bad signature");
  xferExpectRefused([&] { EntryReceiver(e.manifest, "", w.trusted, w.key); }, "unsigned");
  std::string altered = e.manifest;
  altered.replace(altered.find("xfer"), 4, "xfes");
  xferExpectRefused([&] { EntryReceiver(altered, e.signature_hex, w.trusted, w.key); }, "bad signature");
  xferExpectRefused([&] { EntryReceiver(e.manifest, e.signature_hex, w.trusted, keyOf("another")); }, "swapped");
  EXPECT_FALSE(w.targetHasIt());
}

TEST(EntryTransfer, OverTheLimitsIsRefusedBeforeAnyByte) {
  XferWorld w;
  const SignedEntry e = w.sign(true);
  TransferLimits payload_limit;
  payload_limit.max_payload_bytes = e.payloadBytes() - 1;
  xferExpectRefused([&] { EntryReceiver(e.manifest, e.signature_hex, w.trusted, w.key, payload_limit); },
                    "more than the limit of " + std::to_string(e.payloadBytes() - 1));
  TransferLimits manifest_limit;
  manifest_limit.max_manifest_bytes = e.manifest.size() - 1;
  xferExpectRefused([&] { EntryReceiver(e.manifest, e.signature_hex, w.trusted, w.key, manifest_limit); },
                    "the manifest has");
  TransferLimits files_limit;
  files_limit.max_files = 3;
  xferExpectRefused([&] { EntryReceiver(e.manifest, e.signature_hex, w.trusted, w.key, files_limit); },
                    "lists 4 files");
  payload_limit.max_payload_bytes = e.payloadBytes();  // exactly the limit: accepted
  EXPECT_NO_THROW(EntryReceiver(e.manifest, e.signature_hex, w.trusted, w.key, payload_limit));
  EXPECT_FALSE(w.targetHasIt());
}

TEST(EntryTransfer, AnAlteredTruncatedOrOverlongPayloadNeverReachesTheCache) {
  for (const bool sources : {true, false}) {
    SCOPED_TRACE("sources " + std::to_string(sources));
    XferWorld w;
    const SignedEntry e = w.sign(sources);
    const std::string payload = xferPayload(e, 1 << 16);

    std::string altered = payload;
    altered[w.description.size() + 5000] ^= 0x01;  // inside library.so
    EntryReceiver flipped(e.manifest, e.signature_hex, w.trusted, w.key);
    xferAppend(flipped, altered, 7);
    EXPECT_TRUE(flipped.complete());
    xferExpectRefused([&] { flipped.install(w.target); }, "library.so: SHA-256 mismatch");

    EntryReceiver truncated(e.manifest, e.signature_hex, w.trusted, w.key);
    xferAppend(truncated, payload.substr(0, payload.size() - 1), 1000);
    EXPECT_FALSE(truncated.complete());
    xferExpectRefused([&] { truncated.install(w.target); }, "incomplete");

    EntryReceiver overlong(e.manifest, e.signature_hex, w.trusted, w.key);
    xferAppend(overlong, payload.substr(0, 3), 3);
    xferExpectRefused([&] { xferAppend(overlong, payload.substr(3) + "x", payload.size()); }, "more bytes");
    EXPECT_EQ(overlong.received(), 3u) << "the chunk that went past the end was not taken";
    xferAppend(overlong, payload.substr(3), payload.size());
    xferExpectRefused([&] { xferAppend(overlong, "x", 1); }, "more bytes");

    EXPECT_FALSE(w.targetHasIt());
    EXPECT_TRUE(fs::is_empty(w.target.dir() / "staging"));
    // What was refused is still whole on the sending side: the overlong receiver, given
    // exactly the payload, installs.
    EXPECT_EQ(overlong.install(w.target).status, ImportResult::Status::Imported);
  }
}

}  // namespace
}  // namespace robodiff::cache
