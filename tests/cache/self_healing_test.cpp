// The cache heals itself: a library that is missing, truncated, replaced or turned into
// a symbolic link is quarantined (with its reason) and the key can be claimed and built
// again; a lost or empty index is re-created from the objects' entry.json, and objects
// that cannot be verified are quarantined instead of indexed.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "robodiff/cache/cache.hpp"
#include "robodiff/model/canonical.hpp"
#include "cache/cache_fixtures.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::cache {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// Publishes a made-up library of `bytes` bytes whose content depends on `name`.
Artifact healingBuild(Cache& cache, const TempDir& tmp, const std::string& name, std::size_t bytes = 4096) {
  std::string library(bytes, '\0');
  for (std::size_t i = 0; i < bytes; ++i) library[i] = static_cast<char>((i * 131 + name.size() * 7 + name[0]) & 0xff);
  ArtifactFiles f;
  f.library = tmp.file(name + ".so", library);
  f.description = tmp.file(name + ".json", R"({"name":")" + name + R"("})");
  ClaimResult r = cache.claim(keyOf(name), infoFor(name));
  EXPECT_EQ(r.state, ClaimResult::State::Claimed);
  return cache.publish(*r.claim, infoFor(name), f);
}

// The reasons recorded in DIR/quarantine/*/reason, joined.
std::string quarantineReasons(const fs::path& cache_dir) {
  std::string all;
  for (const auto& e : fs::directory_iterator(cache_dir / "quarantine"))
    if (fs::exists(e.path() / "reason")) all += testing::readFile(e.path() / "reason");
  return all;
}

// find() must report a miss (never throw, never hand out the file) and quarantine it;
// the key is then free to be claimed and built again.
void expectQuarantinedAndRebuildable(Cache& cache, const TempDir& tmp, const std::string& name,
                                     const std::string& reason) {
  ::testing::internal::CaptureStderr();
  std::optional<Artifact> found;
  EXPECT_NO_THROW(found = cache.find(keyOf(name)));
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_FALSE(found.has_value());
  EXPECT_NE(log.find(reason), std::string::npos) << log;
  EXPECT_NE(quarantineReasons(cache.dir()).find(reason), std::string::npos);
  EXPECT_FALSE(cache.entry(keyOf(name)));
  const Artifact rebuilt = healingBuild(cache, tmp, name);
  EXPECT_EQ(testing::readFile(rebuilt.library()), testing::readFile(tmp / (name + ".so")));
  EXPECT_TRUE(cache.find(keyOf(name)));
}

// intact(): the cheap look a holder of a library takes (index row and file size, no hash).
TEST(CacheIntact, ReadyWithTheIndexedSizeOnly) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  EXPECT_FALSE(cache.intact(keyOf("absent")));
  const Artifact a = healingBuild(cache, tmp, "whole");
  EXPECT_TRUE(cache.intact(a.key()));
  ::chmod(a.library().c_str(), 0700);
  fs::resize_file(a.library(), 100);
  EXPECT_FALSE(cache.intact(a.key()));
  fs::remove(a.library());
  EXPECT_FALSE(cache.intact(a.key()));
  ClaimResult building = cache.claim(keyOf("building"), infoFor("building"));
  ASSERT_EQ(building.state, ClaimResult::State::Claimed);
  EXPECT_FALSE(cache.intact(keyOf("building")));
  cache.abandon(*building.claim);
}

TEST(CacheSelfHealing, AMissingLibraryIsQuarantinedAndRebuilt) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  fs::remove(healingBuild(cache, tmp, "rnea").library());
  expectQuarantinedAndRebuildable(cache, tmp, "rnea", "library.so is missing");
  EXPECT_EQ(cache.stats().quarantined, 1u);
}

TEST(CacheSelfHealing, AMissingObjectDirectoryIsRecordedAndRebuilt) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  fs::remove_all(healingBuild(cache, tmp, "aba").dir());
  expectQuarantinedAndRebuildable(cache, tmp, "aba", "is missing");
  EXPECT_EQ(cache.stats().quarantined, 1u);
}

TEST(CacheSelfHealing, TruncatedReplacedAndLinkedLibrariesAreQuarantinedAndRebuilt) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  const Artifact other = healingBuild(cache, tmp, "other");

  const fs::path truncated = healingBuild(cache, tmp, "crba").library();
  ::chmod(truncated.c_str(), 0700);
  fs::resize_file(truncated, 1000);
  expectQuarantinedAndRebuildable(cache, tmp, "crba", "truncated or replaced");

  // Another entry's library, same size, in its place.
  const fs::path replaced = healingBuild(cache, tmp, "minv").library();
  ::chmod(replaced.c_str(), 0700);
  fs::remove(replaced);
  fs::copy_file(other.library(), replaced);
  expectQuarantinedAndRebuildable(cache, tmp, "minv", "SHA-256 mismatch");

  const fs::path linked = healingBuild(cache, tmp, "fk").library();
  fs::remove(linked);
  fs::create_symlink(other.library(), linked);
  expectQuarantinedAndRebuildable(cache, tmp, "fk", "symbolic link");

  EXPECT_EQ(cache.stats().quarantined, 3u);
  EXPECT_TRUE(cache.find(keyOf("other")));  // untouched
}

TEST(CacheSelfHealing, AClaimOnAnEntryWhoseLibraryIsGoneIsGrantedForTheRebuild) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  fs::remove(healingBuild(cache, tmp, "rnea").library());
  ::testing::internal::CaptureStderr();
  const ClaimResult r = cache.claim(keyOf("rnea"), infoFor("rnea"));
  ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(r.state, ClaimResult::State::Claimed);
}

TEST(CacheSelfHealing, EveryPublishedEntryCarriesItsRowInEntryJson) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  const Artifact a = healingBuild(cache, tmp, "rnea");
  const nlohmann::json j = nlohmann::json::parse(testing::readFile(a.dir() / "entry.json"));
  EXPECT_EQ(j["key"], keyOf("rnea"));
  EXPECT_EQ(j["library_sha256"], a.entry().library_sha256);
  EXPECT_EQ(j["library_bytes"], a.entry().library_bytes);
  EXPECT_EQ(j["spec"], infoFor("rnea").spec);
  EXPECT_EQ(a.entry().total_bytes, a.entry().library_bytes + fs::file_size(a.description()) +
                                       fs::file_size(a.dir() / "entry.json"));
}

void deleteIndex(const fs::path& cache_dir) {
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(cache_dir / (std::string("index.sqlite") + suffix));
}

TEST(CacheSelfHealing, RepairRecreatesALostIndexAndQuarantinesWhatCannotBeVerified) {
  TempDir tmp;
  std::map<std::string, Entry> before;
  {
    Cache cache = Cache::open(tmp / "cache");
    for (const char* name : {"rnea", "aba", "crba", "bad", "nometa"}) before[name] = healingBuild(cache, tmp, name).entry();
  }
  deleteIndex(tmp / "cache");
  const fs::path bad = tmp / "cache" / "objects" / keyOf("bad").substr(0, 2) / keyOf("bad") / "library.so";
  ::chmod(bad.c_str(), 0700);
  fs::resize_file(bad, 10);
  fs::remove(tmp / "cache" / "objects" / keyOf("nometa").substr(0, 2) / keyOf("nometa") / "entry.json");

  CacheOptions no_auto;
  no_auto.repair_empty_index = false;
  Cache cache = Cache::open(tmp / "cache", no_auto);
  EXPECT_TRUE(cache.list().empty());
  ::testing::internal::CaptureStderr();
  const RepairReport report = cache.repair();
  ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(report.scanned, 5u);
  EXPECT_EQ(report.recovered, 3u);
  ASSERT_EQ(report.quarantined.size(), 2u);
  std::set<std::string> bad_keys;
  for (const VerifyProblem& p : report.quarantined) bad_keys.insert(p.key);
  EXPECT_EQ(bad_keys, (std::set<std::string>{keyOf("bad"), keyOf("nometa")}));
  for (const char* name : {"rnea", "aba", "crba"}) {
    const std::optional<Artifact> a = cache.find(keyOf(name));
    ASSERT_TRUE(a) << name;
    const Entry& was = before[name];
    EXPECT_EQ(a->entry().library_sha256, was.library_sha256);
    EXPECT_EQ(a->entry().total_bytes, was.total_bytes);
    EXPECT_EQ(a->entry().created, was.created);
    EXPECT_EQ(a->entry().info.spec, was.info.spec);
    EXPECT_EQ(a->entry().info.sizes, was.info.sizes);
    EXPECT_EQ(a->entry().info.compiler, was.info.compiler);
    EXPECT_EQ(a->entry().info.model_hash, was.info.model_hash);
    EXPECT_DOUBLE_EQ(a->entry().info.build_seconds, was.info.build_seconds);
  }
  EXPECT_FALSE(cache.entry(keyOf("bad")));
  EXPECT_EQ(cache.stats().quarantined, 2u);
  // A second repair finds everything indexed.
  const RepairReport again = cache.repair();
  EXPECT_EQ(again.recovered, 0u);
  EXPECT_EQ(again.already_indexed, 3u);
  EXPECT_TRUE(again.quarantined.empty());
}

TEST(CacheSelfHealing, OpeningACacheWhoseIndexIsGoneOrEmptyRepairsIt) {
  TempDir tmp;
  {
    Cache cache = Cache::open(tmp / "cache");
    healingBuild(cache, tmp, "rnea");
    healingBuild(cache, tmp, "aba");
  }
  deleteIndex(tmp / "cache");
  {
    ::testing::internal::CaptureStderr();
    Cache cache = Cache::open(tmp / "cache");
    const std::string log = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(log.find("2 recovered, 0 quarantined"), std::string::npos) << log;
    EXPECT_EQ(cache.list().size(), 2u);
  }
  // An index file emptied to zero bytes.
  deleteIndex(tmp / "cache");
  std::ofstream(tmp / "cache" / "index.sqlite").close();
  ::testing::internal::CaptureStderr();
  Cache cache = Cache::open(tmp / "cache");
  ::testing::internal::GetCapturedStderr();
  EXPECT_TRUE(cache.find(keyOf("rnea")));
  EXPECT_TRUE(cache.find(keyOf("aba")));
}

}  // namespace
}  // namespace robodiff::cache
