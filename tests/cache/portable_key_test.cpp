// The portable key (cache_key.hpp): the identity without the compiler's, so that a host
// without the build host's compiler finds a library it imported or fetched
// (Cache::findPortable). It ignores the compiler and nothing else; it is recorded in the
// index, entry.json and the signed manifest; an index made before it gains the column.
#include <sqlite3.h>

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cache_fixtures.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "robodiff/cache/entry_manifest.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/cache/target_check.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::cache {
namespace {

BuildIdentity portableSampleIdentity() {
  BuildIdentity id;
  id.model_hash = "m";
  id.spec = "s";
  id.generator = "g";
  id.compiler = "cc 1.0";
  id.flags = {"-O2", "-fPIC"};
  id.target_cpu = "x86_64 x86-64-v3";
  return id;
}

TEST(PortableKey, IgnoresTheCompilerAndNothingElse) {
  const BuildIdentity base = portableSampleIdentity();
  // The full key is unchanged by the portable key's arrival (existing caches keep theirs).
  EXPECT_EQ(base.key(), sha256Hex("format=robodiff-cache-key 1\nmodel=m\nspec=s\ngenerator=g\ncompiler=cc 1.0\n"
                                  "flags=-O2\x1f-fPIC\x1f\ntarget=x86_64 x86-64-v3\n"));
  BuildIdentity other_compiler = base;
  other_compiler.compiler = "cc 2.0";
  EXPECT_NE(other_compiler.key(), base.key());
  EXPECT_EQ(other_compiler.portableKey(), base.portableKey());
  EXPECT_NE(base.portableKey(), base.key());
  for (std::string BuildIdentity::*field :
       {&BuildIdentity::model_hash, &BuildIdentity::spec, &BuildIdentity::generator, &BuildIdentity::target_cpu}) {
    BuildIdentity changed = base;
    changed.*field += "x";
    EXPECT_NE(changed.portableKey(), base.portableKey());
  }
  BuildIdentity other_flags = base;
  other_flags.flags.push_back("-ffast-math");
  EXPECT_NE(other_flags.portableKey(), base.portableKey());
}

TEST(PortableKey, IsPreparedWithoutACompiler) {
  const Model arm = loadUrdfFile((testing::sourceDir() / "examples/robots/arm7.urdf").string());
  const FunctionSpec spec = parseFunctionSpec(
      R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"target": "x86-64-v2"}})", "spec");
  const std::string hash = canonicalHash(arm);
  EXPECT_THROW(prepareBuild(arm, hash, spec, "", "/nonexistent/cc"), std::exception);
  const std::string portable = preparePortableKey(hash, spec, "");
  EXPECT_TRUE(isCacheKey(portable));
  const PreparedBuild prepared = prepareBuild(arm, hash, spec, "", "");
  EXPECT_EQ(prepared.info.portable_key, portable);
  EXPECT_EQ(prepared.identity.portableKey(), portable);
  EXPECT_NE(preparePortableKey(hash, spec, "arm_rnea"), portable) << "the C name is in the library";
}

// A spec's own key first, then the same spec built for each x86-64 level this CPU runs,
// highest first, each as parseFunctionSpec makes a spec naming that level.
TEST(PortableKey, ForASpecAskingForNativeAlsoEveryLevelThisCpuRuns) {
  const std::string hash = sha256Hex("a model");
  const std::string body = R"({"function": "rnea", "outputs": [{"kind": "value"}])";
  const FunctionSpec native = parseFunctionSpec(body + "}", "spec");
  std::vector<std::string> expected{preparePortableKey(hash, native, "")};
  for (const std::string level : {"x86-64-v4", "x86-64-v3", "x86-64-v2"})
    if (cpuSupportsLevel(level))
      expected.push_back(
          preparePortableKey(hash, parseFunctionSpec(body + R"(, "build": {"target": ")" + level + R"("}})", level), ""));
  const std::vector<std::string> keys = portableKeysFor(hash, native, "");
  EXPECT_EQ(keys, expected);
  EXPECT_EQ(std::set<std::string>(keys.begin(), keys.end()).size(), keys.size()) << "one key per level";
  EXPECT_EQ(portableKeysFor(hash, native, "arm_rnea").front(), preparePortableKey(hash, native, "arm_rnea"));
  // A spec that names its target (a level, or any x86-64) has just its own key.
  for (const std::string target : {"x86-64-v2", "x86-64"}) {
    const FunctionSpec named = parseFunctionSpec(body + R"(, "build": {"target": ")" + target + R"("}})", target);
    EXPECT_EQ(portableKeysFor(hash, named, ""), std::vector<std::string>{preparePortableKey(hash, named, "")}) << target;
  }
}

// An entry with `portable_key` built for `target` (a targetLabel).
Artifact publishPortable(Cache& cache, const testing::TempDir& tmp, const std::string& name,
                         const std::string& portable_key, const std::string& target) {
  EntryInfo info = infoFor(name);
  info.compiler += " target=" + target;
  info.portable_key = portable_key;
  ClaimResult r = cache.claim(keyOf(name), info);
  EXPECT_EQ(r.state, ClaimResult::State::Claimed);
  ArtifactFiles files;
  files.library = tmp.file(name + ".so", "library of " + name);
  files.description = tmp.file(name + ".json", "{}");
  return cache.publish(*r.claim, info, files);
}

TEST(PortableKey, FindsAnEntryThisCpuCanRun) {
  testing::TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  const std::string pk = sha256Hex("portable");
  EXPECT_FALSE(cache.findPortable(pk));
  publishPortable(cache, tmp, "here", pk, "generic");
  publishPortable(cache, tmp, "elsewhere", pk, "native:0000000000000000");  // newer, another CPU's
  const std::optional<Artifact> found = cache.findPortable(pk);
  ASSERT_TRUE(found);
  EXPECT_EQ(found->key(), keyOf("here"));
  EXPECT_EQ(found->entry().info.portable_key, pk);
  EXPECT_FALSE(cache.findPortable(sha256Hex("another function")));
  EXPECT_THROW(cache.findPortable("' OR 1=1 --"), std::invalid_argument);
  // A claim still building is not served.
  EntryInfo building = infoFor("building");
  building.portable_key = sha256Hex("building pk");
  ASSERT_EQ(cache.claim(keyOf("building"), building).state, ClaimResult::State::Claimed);
  EXPECT_FALSE(cache.findPortable(building.portable_key));
}

TEST(PortableKey, IsKeptByEntryJsonAndTheSignedManifest) {
  testing::TempDir tmp;
  const std::string pk = sha256Hex("kept");
  {
    Cache cache = Cache::open(tmp / "cache");
    publishPortable(cache, tmp, "kept", pk, "generic");
  }
  std::filesystem::remove(tmp / "cache" / "index.sqlite");  // repair rebuilds it from entry.json
  Cache repaired = Cache::open(tmp / "cache");
  ASSERT_TRUE(repaired.entry(keyOf("kept")));
  EXPECT_EQ(repaired.entry(keyOf("kept"))->info.portable_key, pk);
  ASSERT_TRUE(repaired.findPortable(pk));

  EntryManifest m;
  m.key = keyOf("kept");
  m.info = infoFor("kept");
  m.files = {{"description.json", 2, sha256Hex("{}")}, {"library.so", 3, sha256Hex("lib")}};
  m.info.portable_key = pk;
  EXPECT_EQ(parseManifest(manifestText(m)).info.portable_key, pk);
  m.info.portable_key.clear();  // a manifest from before: no field, and it still parses
  EXPECT_EQ(manifestText(m).find("portable_key"), std::string::npos);
  EXPECT_EQ(parseManifest(manifestText(m)).info.portable_key, "");
}

TEST(PortableKey, AnOlderIndexGainsTheColumn) {
  testing::TempDir tmp;
  std::filesystem::create_directories(tmp / "cache");
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((tmp / "cache" / "index.sqlite").c_str(), &db), SQLITE_OK);
  // The entries table as the first schema made it, with a row left by a dead builder.
  const std::string first_schema =
      "CREATE TABLE entries (key TEXT PRIMARY KEY, state TEXT NOT NULL, model_hash TEXT NOT NULL DEFAULT '', "
      "robot TEXT NOT NULL DEFAULT '', function TEXT NOT NULL DEFAULT '', spec TEXT NOT NULL DEFAULT '', "
      "sizes TEXT NOT NULL DEFAULT '', compiler TEXT NOT NULL DEFAULT '', build_seconds REAL NOT NULL DEFAULT 0, "
      "library_bytes INTEGER NOT NULL DEFAULT 0, total_bytes INTEGER NOT NULL DEFAULT 0, "
      "library_sha256 TEXT NOT NULL DEFAULT '', created INTEGER NOT NULL DEFAULT 0, "
      "last_used INTEGER NOT NULL DEFAULT 0, hits INTEGER NOT NULL DEFAULT 0, owner TEXT NOT NULL DEFAULT '', "
      "lease_expires_ms INTEGER NOT NULL DEFAULT 0);"
      "INSERT INTO entries (key, state, owner, lease_expires_ms) VALUES ('" + keyOf("old") + "', 'building', 'gone', 1);";
  ASSERT_EQ(sqlite3_exec(db, first_schema.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
  Cache cache = Cache::open(tmp / "cache");
  ASSERT_TRUE(cache.entry(keyOf("old")));
  EXPECT_EQ(cache.entry(keyOf("old"))->info.portable_key, "");
  const std::string pk = sha256Hex("new");
  publishPortable(cache, tmp, "new", pk, "generic");
  EXPECT_EQ(cache.entry(keyOf("new"))->info.portable_key, pk);
  EXPECT_TRUE(cache.findPortable(pk));
}

}  // namespace
}  // namespace robodiff::cache
