// Signed bundles of cache entries on real caches (real directories, real SQLite):
// export -> import round trip, and every way a bundle can be wrong (unsigned, unknown key,
// altered signature, manifest or library, a swapped library or directory, path
// traversal, links, extra, missing or duplicate files, truncation, absurd sizes). A refused
// entry leaves the cache exactly as it was; the other entries of the bundle still import.
// Artifacts are made-up files: the cache stores and hashes them, nothing loads them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cache/bundle_members.hpp"
#include "cache/cache_fixtures.hpp"
#include "robodiff/cache/artifact_bundle.hpp"
#include "robodiff/cache/entry_json.hpp"
#include "robodiff/cache/entry_manifest.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::cache {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;
using testing_bundle::member;
using testing_bundle::Member;
using Status = ImportResult::Status;

// A source cache with entries a and b (equal-sized, different libraries), a key that
// signs them, a bundle of both, and a target cache holding c (from another bundle).
struct BundleWorld {
  TempDir tmp;
  Cache source = Cache::open(tmp / "source");
  Cache target = Cache::open(tmp / "target");
  SigningKey signer = SigningKey::generate();
  TrustedKeys trusted;
  std::string a = keyOf("a"), b = keyOf("b"), c = keyOf("c");
  fs::path bundle = tmp / "bundle.tar";

  BundleWorld() {
    trusted.add(signer.publicKey());
    for (const char* name : {"a", "b", "c"}) publish(name);
    exportBundle(source, {c}, signer, tmp / "c.tar");
    const ImportReport r = importBundle(target, tmp / "c.tar", trusted);
    EXPECT_EQ(r.count(Status::Imported), 1u);
    exportBundle(source, {a, b}, signer, bundle);
  }

  void publish(const std::string& name) {
    std::string library(6000, '\0');
    for (std::size_t i = 0; i < library.size(); ++i) library[i] = static_cast<char>((i * 7 + name[0]) & 0xff);
    ArtifactFiles files{tmp.file(name + ".so", library), tmp.file(name + ".json", R"({"name":")" + name + R"("})"),
                        {tmp.file(name + "_part0.c", "double " + name + "(double x) { return x; }\n")}};
    ClaimResult r = source.claim(keyOf(name), infoFor(name));
    ASSERT_EQ(r.state, ClaimResult::State::Claimed);
    source.publish(*r.claim, infoFor(name), files);
  }

  // Everything a refusal must leave alone: every index row and the staging and
  // quarantine directories.
  std::string targetState() {
    nlohmann::json rows = nlohmann::json::array();
    for (const Entry& e : target.list()) rows.push_back(entryJson(e));
    std::string state = rows.dump();
    for (const char* dir : {"staging", "quarantine"})
      for (const auto& e : fs::directory_iterator(target.dir() / dir)) state += "\n" + e.path().string();
    return state;
  }
};

const ImportResult* resultFor(const ImportReport& report, const std::string& key) {
  for (const ImportResult& r : report.entries)
    if (r.key == key) return &r;
  return nullptr;
}

std::string describeReport(const ImportReport& report) {
  std::string s;
  for (const ImportResult& r : report.entries)
    s += "  " + r.key.substr(0, 12) + " " + std::to_string(static_cast<int>(r.status)) + " " + r.problem + "\n";
  return s;
}

TEST(ArtifactBundle, ExportThenImportGivesTheSameVerifiedEntries) {
  BundleWorld w;
  const ImportReport report = importBundle(w.target, w.bundle, w.trusted);
  ASSERT_EQ(report.entries.size(), 2u) << describeReport(report);
  EXPECT_EQ(report.count(Status::Imported), 2u) << describeReport(report);
  for (const std::string& key : {w.a, w.b}) {
    const std::optional<Artifact> got = w.target.find(key);
    const std::optional<Artifact> original = w.source.find(key);
    ASSERT_TRUE(got && original) << key;
    EXPECT_EQ(testing::readFile(got->library()), testing::readFile(original->library()));
    EXPECT_EQ(testing::readFile(got->description()), testing::readFile(original->description()));
    EXPECT_EQ(got->entry().library_sha256, original->entry().library_sha256);
    EXPECT_EQ(got->entry().info.spec, original->entry().info.spec);
    EXPECT_EQ(got->entry().info.compiler, original->entry().info.compiler);
    EXPECT_EQ(got->entry().info.model_hash, original->entry().info.model_hash);
    EXPECT_EQ(got->entry().total_bytes, original->entry().total_bytes);  // sources included
    EXPECT_EQ(resultFor(report, key)->signer, w.signer.keyId());
    EXPECT_EQ(resultFor(report, key)->function, key == w.a ? "a" : "b");
  }
  EXPECT_TRUE(w.target.verify().problems.empty());

  // Again: already present and intact, left alone.
  const ImportReport again = importBundle(w.target, w.bundle, w.trusted);
  EXPECT_EQ(again.count(Status::Present), 2u) << describeReport(again);
  EXPECT_TRUE(again.allAccepted());
}

TEST(ArtifactBundle, TheManifestIsCanonicalSignedJsonOfTheEntry) {
  BundleWorld w;
  std::vector<Member> members = testing_bundle::readMembers(w.bundle);
  const std::string text = member(members, w.a + "/manifest.json").bytes;
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j.dump(), text) << "not canonical (sorted keys, compact)";
  EXPECT_EQ(j["key"], w.a);
  EXPECT_EQ(j["signer"], w.signer.keyId());
  EXPECT_EQ(j["entry"]["compiler"], infoFor("a").compiler);
  EXPECT_EQ(j["entry"]["model_hash"], infoFor("a").model_hash);
  const std::string library = member(members, w.a + "/library.so").bytes;
  bool listed = false;
  for (const auto& f : j["files"])
    if (f["name"] == "library.so") {
      listed = true;
      EXPECT_EQ(f["size"], library.size());
      EXPECT_EQ(f["sha256"], sha256Hex(library));
    }
  EXPECT_TRUE(listed);
  std::string sig = member(members, w.a + "/manifest.sig").bytes;
  ASSERT_EQ(sig.size(), 129u);
  EXPECT_TRUE(w.signer.publicKey().verify(text, fromHex(sig.substr(0, 128))));
  EXPECT_NO_THROW(parseManifest(text));
}

// One way to spoil entry a of the bundle, and what the refusal must say.
struct Tamper {
  const char* name;
  std::function<void(std::vector<Member>&, BundleWorld&)> apply;
  const char* expected;
  bool a_renamed = false;  // the spoiled entry arrives under another key than a
};

void PrintTo(const Tamper& t, std::ostream* out) { *out << t.name; }

void eraseMember(std::vector<Member>& members, const std::string& name) {
  std::erase_if(members, [&](const Member& m) { return m.name == name; });
}

std::vector<Tamper> tamperings() {
  return {
      {"Unsigned", [](auto& m, auto& w) { eraseMember(m, w.a + "/manifest.sig"); }, "unsigned: it has no manifest.sig"},
      {"UnknownKey",
       [](auto& m, auto& w) {
         const SigningKey stranger = SigningKey::generate();
         nlohmann::json j = nlohmann::json::parse(member(m, w.a + "/manifest.json").bytes);
         j["signer"] = stranger.keyId();
         member(m, w.a + "/manifest.json").bytes = j.dump();
         member(m, w.a + "/manifest.sig").bytes = toHex(stranger.sign(j.dump())) + "\n";
       },
       "unknown key"},
      {"FlippedSignature",
       [](auto& m, auto& w) {
         std::string& sig = member(m, w.a + "/manifest.sig").bytes;
         sig[5] = sig[5] == '0' ? '1' : '0';
       },
       "bad signature"},
      {"FlippedManifest",
       [](auto& m, auto& w) {
         std::string& text = member(m, w.a + "/manifest.json").bytes;
         text.replace(text.find("arm7"), 4, "arm8");
       },
       "bad signature"},
      {"FlippedLibraryByte", [](auto& m, auto& w) { member(m, w.a + "/library.so").bytes[100] ^= 0x01; },
       "library.so: SHA-256 mismatch"},
      {"SwappedLibrary",
       [](auto& m, auto& w) { member(m, w.a + "/library.so").bytes = member(m, w.b + "/library.so").bytes; },
       "library.so: SHA-256 mismatch"},
      {"SwappedDirectory",
       [](auto& m, auto& w) {
         for (Member& x : m)
           if (x.name.rfind(w.a + "/", 0) == 0) x.name = keyOf("d") + x.name.substr(w.a.size());
       },
       "swapped: the signed manifest is for entry", true},
      {"TruncatedLibrary",
       [](auto& m, auto& w) { member(m, w.a + "/library.so").bytes.resize(3000); }, "truncated or replaced"},
      {"PathTraversal", [](auto& m, auto& w) { m.push_back({w.a + "/../../evil.so", "x"}); }, "unsafe member name"},
      {"SourcePathTraversal", [](auto& m, auto& w) { m.push_back({w.a + "/src/../../../x.c", "x"}); },
       "unsafe member name"},
      {"AbsolutePath", [](auto& m, auto& w) { m.push_back({w.a + "//etc/passwd", "x"}); }, "unsafe member name"},
      {"ExtraFile", [](auto& m, auto& w) { m.push_back({w.a + "/src/extra.c", "int x;"}); },
       "extra file src/extra.c"},
      {"MissingFile", [](auto& m, auto& w) { eraseMember(m, w.a + "/description.json"); },
       "missing file description.json"},
      {"SymbolicLink",
       [](auto& m, auto& w) {
         Member& lib = member(m, w.a + "/library.so");
         lib.symlink = true;
         lib.bytes = "/usr/lib/x86_64-linux-gnu/libc.so.6";
       },
       "not a regular file"},
      {"DuplicateMember", [](auto& m, auto& w) { m.push_back({w.a + "/library.so", "second"}); }, "appears twice"},
  };
}

class TamperedBundle : public ::testing::TestWithParam<Tamper> {};

TEST_P(TamperedBundle, TheEntryIsRefusedAndNothingOfItReachesTheCache) {
  BundleWorld w;
  std::vector<Member> members = testing_bundle::readMembers(w.bundle);
  GetParam().apply(members, w);
  const fs::path tampered = w.tmp / "tampered.tar";
  testing_bundle::writeMembers(tampered, members);

  // Alone (b's members dropped): the cache is exactly as it was.
  std::vector<Member> only_a = members;
  std::erase_if(only_a, [&](const Member& m) { return m.name.rfind(w.b + "/", 0) == 0 || m.name == kBundleIndexName; });
  testing_bundle::writeMembers(w.tmp / "only_a.tar", only_a);
  const std::string before = w.targetState();
  const ImportReport alone = importBundle(w.target, w.tmp / "only_a.tar", w.trusted);
  EXPECT_FALSE(alone.allAccepted());
  EXPECT_EQ(alone.count(Status::Imported), 0u) << describeReport(alone);
  EXPECT_EQ(w.targetState(), before);

  // With b: a is refused, naming the problem; b is imported.
  const ImportReport report = importBundle(w.target, tampered, w.trusted);
  const std::string spoiled = GetParam().a_renamed ? keyOf("d") : w.a;
  const ImportResult* ra = resultFor(report, spoiled);
  ASSERT_NE(ra, nullptr) << describeReport(report);
  EXPECT_EQ(ra->status, Status::Refused);
  EXPECT_NE(ra->problem.find(GetParam().expected), std::string::npos) << ra->problem;
  const ImportResult* rb = resultFor(report, w.b);
  ASSERT_NE(rb, nullptr) << describeReport(report);
  EXPECT_EQ(rb->status, Status::Imported) << rb->problem;
  EXPECT_FALSE(report.allAccepted());

  EXPECT_FALSE(w.target.entry(spoiled).has_value()) << "an index row was left for the refused entry";
  EXPECT_FALSE(w.target.find(w.a).has_value());
  EXPECT_TRUE(w.target.find(w.b).has_value());
  EXPECT_TRUE(fs::is_empty(w.target.dir() / "staging"));
  EXPECT_TRUE(fs::is_empty(w.target.dir() / "quarantine"));
  EXPECT_FALSE(fs::exists(w.target.dir() / "objects" / spoiled.substr(0, 2) / spoiled));
  EXPECT_TRUE(w.target.verify().problems.empty());
}

INSTANTIATE_TEST_SUITE_P(ArtifactBundle, TamperedBundle, ::testing::ValuesIn(tamperings()),
                         [](const ::testing::TestParamInfo<Tamper>& info) { return std::string(info.param.name); });

// Cut inside an entry: that entry is refused as truncated, and the cut is reported.
TEST(ArtifactBundle, ABundleCutShortIsRefusedAndLeavesNothing) {
  BundleWorld w;
  const std::string bytes = testing::readFile(w.bundle);
  std::vector<Member> members = testing_bundle::readMembers(w.bundle);
  const std::string library = member(members, w.a + "/library.so").bytes;
  const std::size_t inside_library = bytes.find(library.substr(0, 64)) + 2000;
  std::ofstream(w.tmp / "cut.tar", std::ios::binary) << bytes.substr(0, inside_library);
  const std::string before = w.targetState();
  const ImportReport report = importBundle(w.target, w.tmp / "cut.tar", w.trusted);
  ASSERT_NE(resultFor(report, w.a), nullptr) << describeReport(report);
  EXPECT_NE(resultFor(report, w.a)->problem.find("truncated"), std::string::npos) << describeReport(report);
  EXPECT_EQ(resultFor(report, w.b), nullptr) << "b lies after the cut";
  const ImportResult* cut = resultFor(report, kBundleIndexName);
  ASSERT_NE(cut, nullptr) << describeReport(report);
  EXPECT_NE(cut->problem.find("entries after this point are missing"), std::string::npos) << cut->problem;
  EXPECT_EQ(w.targetState(), before);
}

// Cut between entries: the complete ones import; the missing bundle.json tells of the cut.
TEST(ArtifactBundle, ABundleCutBetweenEntriesImportsWhatIsWholeAndSaysItWasCut) {
  BundleWorld w;
  std::vector<Member> members = testing_bundle::readMembers(w.bundle);
  std::erase_if(members, [&](const Member& m) { return m.name.rfind(w.b + "/", 0) == 0 || m.name == kBundleIndexName; });
  testing_bundle::writeMembers(w.tmp / "cut.tar", members);
  const ImportReport report = importBundle(w.target, w.tmp / "cut.tar", w.trusted);
  EXPECT_EQ(resultFor(report, w.a)->status, Status::Imported);
  const ImportResult* cut = resultFor(report, kBundleIndexName);
  ASSERT_NE(cut, nullptr) << describeReport(report);
  EXPECT_NE(cut->problem.find("truncated"), std::string::npos) << cut->problem;
  EXPECT_FALSE(report.allAccepted());
}

TEST(ArtifactBundle, AbsurdSizesAreRefusedFromTheHeaderBeforeReading) {
  BundleWorld w;
  BundleLimits limits;
  limits.max_file_bytes = 1000;  // the libraries have 6000 bytes
  const std::string before = w.targetState();
  const ImportReport report = importBundle(w.target, w.bundle, w.trusted, limits);
  EXPECT_EQ(report.count(Status::Refused), 2u) << describeReport(report);
  EXPECT_NE(resultFor(report, w.a)->problem.find("more than the limit of 1000"), std::string::npos)
      << resultFor(report, w.a)->problem;
  EXPECT_EQ(w.targetState(), before);
}

TEST(ArtifactBundle, MembersOfNoEntryAreReportedAndTheRestImports) {
  BundleWorld w;
  std::vector<Member> members = testing_bundle::readMembers(w.bundle);
  members.insert(members.begin(), {"../outside.so", "x"});
  testing_bundle::writeMembers(w.tmp / "stray.tar", members);
  const ImportReport report = importBundle(w.target, w.tmp / "stray.tar", w.trusted);
  const ImportResult* stray = resultFor(report, "../outside.so");
  ASSERT_NE(stray, nullptr) << describeReport(report);
  EXPECT_NE(stray->problem.find("belongs to no entry"), std::string::npos) << stray->problem;
  EXPECT_EQ(report.count(Status::Imported), 2u) << describeReport(report);
  EXPECT_FALSE(fs::exists(w.tmp.path().parent_path() / "outside.so"));
}

TEST(ArtifactBundle, AKeyNamedTwiceIsExportedOnce) {
  BundleWorld w;
  const ExportReport exported = exportBundle(w.source, {w.a, w.a}, w.signer, w.tmp / "twice.tar");
  EXPECT_EQ(exported.exported.size(), 1u);
  const ImportReport report = importBundle(w.target, w.tmp / "twice.tar", w.trusted);
  EXPECT_TRUE(report.allAccepted()) << describeReport(report);
  EXPECT_EQ(report.count(Status::Imported), 1u);
}

TEST(ArtifactBundle, ExportRefusesAnAbsentOrDamagedEntryAndWritesNothing) {
  BundleWorld w;
  const fs::path out = w.tmp / "none.tar";
  EXPECT_THROW(exportBundle(w.source, {w.a, keyOf("nope")}, w.signer, out), std::runtime_error);
  EXPECT_FALSE(fs::exists(out));
  // A damaged library is caught by the verification before export (and quarantined).
  const fs::path library = w.source.find(w.b)->library();
  fs::permissions(library, fs::perms::owner_write, fs::perm_options::add);
  std::ofstream(library, std::ios::binary | std::ios::app) << "extra";
  try {
    exportBundle(w.source, {w.b}, w.signer, out);
    ADD_FAILURE() << "a damaged entry was exported";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("failed verification"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out.string() + ".partial"));
}

}  // namespace
}  // namespace robodiff::cache
