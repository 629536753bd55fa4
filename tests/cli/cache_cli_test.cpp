// `robodiff cache ls|stat|verify|gc|rm` on a real cache filled by `robodiff warmup`:
// corrupt artifacts found and rebuilt, eviction to a budget, removal by key prefix.
// The compiler is a wrapper that logs its command lines (one -shared command per
// build); specs are built at -O0 without -march=native, on arm7 only.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/cache_workspace.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using nlohmann::json;
using testing::runCommand;
using testing::shellQuote;
using testing::TempDir;
namespace fs = std::filesystem;

using testing::cli;
using testing::countOf;

// The shared workspace, with the warmup and cache commands on it.
struct CacheWorkspace : testing::CacheWorkspace {

  testing::ProcessResult warmup(const std::vector<std::string>& examples) const {
    std::string specs;
    for (const std::string& e : examples) specs.append(" ").append(shellQuote(spec(e).string()));
    return runCommand(cli("warmup --urdf " + shellQuote((testing::sourceDir() / "examples/robots/arm7.urdf").string()) +
                          " --spec" + specs + " --jobs 2 --cache " + shellQuote(cache.string()) + " --compiler " +
                          shellQuote(cc.string())));
  }

  // `robodiff cache ARGS --cache DIR`.
  testing::ProcessResult cacheCommand(const std::string& args) const {
    return runCommand(cli("cache " + args + " --cache " + shellQuote(cache.string())));
  }
  json cacheJson(const std::string& args) const {
    testing::ProcessResult r = cacheCommand(args + " --json");
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.out << r.err;
    return r.exit_code == 0 ? json::parse(r.out) : json();
  }

  // DIR/objects/*/KEY/library.so; an empty path when there is none.
  fs::path library(const std::string& key) const {
    if (fs::is_directory(cache / "objects"))
      for (const auto& shard : fs::directory_iterator(cache / "objects"))
        if (fs::exists(shard.path() / key / "library.so")) return shard.path() / key / "library.so";
    return {};
  }
};

enum class Damage { FlipOneByte, TruncateToHalf };
void PrintTo(Damage d, std::ostream* out) { *out << (d == Damage::FlipOneByte ? "one byte flipped" : "truncated"); }

void damage(const fs::path& library, Damage how) {
  fs::permissions(library, fs::perms::owner_write, fs::perm_options::add);
  std::string bytes = testing::readFile(library);
  ASSERT_GT(bytes.size(), 100u);
  if (how == Damage::FlipOneByte)
    bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);
  else
    bytes.resize(bytes.size() / 2);
  std::ofstream(library, std::ios::binary | std::ios::trunc) << bytes;
}

class DamagedLibrary : public ::testing::TestWithParam<Damage> {};

// verify finds the damage (status 2, naming the key), moves the entry aside, and the
// next warmup builds it again.
TEST_P(DamagedLibrary, VerifyReportsItAndWarmupRebuildsIt) {
  CacheWorkspace w;
  ASSERT_EQ(w.warmup({"crba"}).exit_code, 0);
  const json entries = w.cacheJson("ls");
  ASSERT_EQ(entries.size(), 1u);
  const std::string key = entries[0]["key"];
  ASSERT_TRUE(fs::is_regular_file(w.library(key))) << w.library(key);
  damage(w.library(key), GetParam());

  testing::ProcessResult r = w.cacheCommand("verify");
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.out.find(key.substr(0, 12)), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("crba"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 entry checked, 1 problem (moved to quarantine"), std::string::npos) << r.out;
  EXPECT_TRUE(w.cacheJson("ls").empty());
  EXPECT_GE(w.cacheJson("stat")["quarantined"].get<std::uint64_t>(), 1u);

  r = w.warmup({"crba"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("done "), std::string::npos) << r.out;  // built, not cached
  EXPECT_EQ(r.out.find("cached "), std::string::npos) << r.out;
  EXPECT_EQ(w.builds(), 2u);
  r = w.cacheCommand("verify");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("1 entry checked, no problems"), std::string::npos) << r.out;
}

INSTANTIATE_TEST_SUITE_P(CacheCli, DamagedLibrary, ::testing::Values(Damage::FlipOneByte, Damage::TruncateToHalf),
                         [](const ::testing::TestParamInfo<Damage>& info) {
                           return info.param == Damage::FlipOneByte ? "BitFlip" : "Truncated";
                         });

// Without verify, the hash check at lookup catches the damage: rebuilt, never served.
TEST(CacheCli, WarmupRebuildsADamagedLibraryItFinds) {
  CacheWorkspace w;
  ASSERT_EQ(w.warmup({"crba"}).exit_code, 0);
  const std::string key = w.cacheJson("ls")[0]["key"];
  damage(w.library(key), Damage::FlipOneByte);
  testing::ProcessResult r = w.warmup({"crba"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("done "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("cached "), std::string::npos) << r.out;
  EXPECT_EQ(w.builds(), 2u);
  EXPECT_EQ(w.cacheCommand("verify").exit_code, 0);
}

// A library deleted from the cache: warmup quarantines the entry and builds it again.
TEST(CacheCli, WarmupRebuildsADeletedLibrary) {
  CacheWorkspace w;
  ASSERT_EQ(w.warmup({"crba"}).exit_code, 0);
  const std::string key = w.cacheJson("ls")[0]["key"];
  fs::remove(w.library(key));
  testing::ProcessResult r = w.warmup({"crba"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("done "), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("library.so is missing"), std::string::npos) << r.err;
  EXPECT_EQ(w.builds(), 2u);
  EXPECT_TRUE(fs::is_regular_file(w.library(key)));
  EXPECT_EQ(w.cacheCommand("verify").exit_code, 0);
}

// The index deleted: `cache repair` re-creates every good entry from the objects (a
// damaged one is quarantined), and the next warmup finds them without compiling.
TEST(CacheCli, RepairRecoversALostIndexAndTheNextUseIsAHit) {
  CacheWorkspace w;
  ASSERT_EQ(w.warmup({"crba", "nle", "rnea_jacobian"}).exit_code, 0);
  const json before = w.cacheJson("ls");
  ASSERT_EQ(before.size(), 3u);
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(w.cache / (std::string("index.sqlite") + suffix));
  const std::string damaged_key = before[0]["key"];
  damage(w.library(damaged_key), Damage::TruncateToHalf);

  testing::ProcessResult r = w.cacheCommand("repair");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("2 recovered, 1 quarantined, 0 already indexed (3 object directories scanned)"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find(damaged_key.substr(0, 12)), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("truncated"), std::string::npos) << r.out;
  const json after = w.cacheJson("ls");
  ASSERT_EQ(after.size(), 2u) << after.dump(2);
  for (const json& e : after) {
    for (const json& b : before) {
      if (b["key"] != e["key"]) continue;
      EXPECT_EQ(e["library_sha256"], b["library_sha256"]);
      EXPECT_EQ(e["function"], b["function"]);
      EXPECT_EQ(e["total_bytes"], b["total_bytes"]);
    }
  }
  const json again = w.cacheJson("repair");
  EXPECT_EQ(again["recovered"], 0);
  EXPECT_EQ(again["already_indexed"], 2);

  r = w.warmup({"crba", "nle", "rnea_jacobian"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(countOf(r.out, "cached "), 2u) << r.out;
  EXPECT_EQ(w.builds(), 4u);  // only the quarantined one compiled again
  EXPECT_EQ(w.cacheCommand("verify").exit_code, 0);
}

TEST(CacheCli, LsStatRmAndGcAgree) {
  CacheWorkspace w;
  ASSERT_EQ(w.warmup({"crba", "nle", "rnea_jacobian"}).exit_code, 0);
  json entries = w.cacheJson("ls");
  ASSERT_EQ(entries.size(), 3u) << entries.dump(2);
  std::uint64_t total = 0;
  for (const json& e : entries) total += e["total_bytes"].get<std::uint64_t>();

  json stat = w.cacheJson("stat");
  EXPECT_EQ(stat["dir"], w.cache.string());
  EXPECT_EQ(stat["entries"], 3);
  EXPECT_EQ(stat["building"], 0);
  EXPECT_EQ(stat["bytes"].get<std::uint64_t>(), total);
  EXPECT_EQ(stat["quarantined"], 0);

  // The table: key prefixes, the robot, the functions.
  testing::ProcessResult r = w.cacheCommand("ls");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const json& e : entries) {
    EXPECT_NE(r.out.find(e["key"].get<std::string>().substr(0, 12)), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(e["function"].get<std::string>()), std::string::npos) << r.out;
  }
  EXPECT_NE(r.out.find("arm7"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("3 entries"), std::string::npos) << r.out;

  // rm: a prefix too short or matching nothing removes nothing; 8 digits remove one.
  const std::string removed_key = entries[0]["key"];
  r = w.cacheCommand("rm " + removed_key.substr(0, 4));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("8 or more hex digits"), std::string::npos) << r.err;
  r = w.cacheCommand("rm " + std::string(removed_key[0] == '0' ? "ffffffff" : "00000000"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no entry"), std::string::npos) << r.err;
  EXPECT_EQ(w.cacheJson("ls").size(), 3u);
  r = w.cacheCommand("rm " + removed_key.substr(0, 8));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("removed 1 entry"), std::string::npos) << r.out;
  EXPECT_TRUE(w.library(removed_key).empty());
  entries = w.cacheJson("ls");
  ASSERT_EQ(entries.size(), 2u);
  std::uint64_t left = 0;
  for (const json& e : entries) {
    EXPECT_NE(e["key"], removed_key);
    left += e["total_bytes"].get<std::uint64_t>();
  }
  stat = w.cacheJson("stat");
  EXPECT_EQ(stat["entries"], 2);
  EXPECT_EQ(stat["bytes"].get<std::uint64_t>(), left);

  // gc to one byte evicts everything (nothing is in use).
  const json gc = w.cacheJson("gc --budget 1");
  EXPECT_EQ(gc["evicted"].size(), 2u) << gc.dump(2);
  EXPECT_EQ(gc["freed_bytes"].get<std::uint64_t>(), left);
  EXPECT_EQ(gc["bytes_after"], 0);
  EXPECT_EQ(gc["kept_in_use"], 0);
  EXPECT_TRUE(w.cacheJson("ls").empty());
  stat = w.cacheJson("stat");
  EXPECT_EQ(stat["entries"], 0);
  EXPECT_EQ(stat["bytes"], 0);
  for (const json& e : entries) EXPECT_TRUE(w.library(e["key"]).empty());
}

TEST(CacheCli, SizesAreReadAndShownForPeople) {
  CacheWorkspace w;
  ASSERT_EQ(w.warmup({"crba"}).exit_code, 0);
  testing::ProcessResult r = w.cacheCommand("stat --budget 1.5GiB");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("budget       1.5 GiB"), std::string::npos) << r.out;
  EXPECT_EQ(w.cacheJson("stat --budget 500M")["budget_bytes"], 500u << 20);
  EXPECT_EQ(w.cacheJson("stat --budget 2GB")["budget_bytes"], 2000000000u);
  EXPECT_EQ(w.cacheJson("stat --budget 4096")["budget_bytes"], 4096u);
  r = w.cacheCommand("gc --budget 12parsecs");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("'12parsecs' is not a size"), std::string::npos) << r.err;
  EXPECT_EQ(w.cacheJson("ls").size(), 1u);
}

TEST(CacheCli, AMissingCacheIsEmptyAndAnUnsafeOneIsRefused) {
  TempDir tmp;
  testing::ProcessResult r = runCommand(cli("cache ls --json --cache " + shellQuote((tmp / "none").string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out), json::array());
  EXPECT_NE(r.err.find("no cache at"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "none"));

  const fs::path open = tmp / "open";
  fs::create_directory(open);
  fs::permissions(open, fs::perms::all);
  r = runCommand(cli("cache ls --cache " + shellQuote(open.string())));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(open.string()), std::string::npos) << r.err;
}

TEST(CacheCli, HelpSaysWhatEachSubcommandDoesAndTheExitStatus) {
  for (const std::string sub : {"", "ls", "stat", "verify", "repair", "gc", "rm"}) {
    SCOPED_TRACE(sub);
    testing::ProcessResult r = runCommand(cli("cache " + sub + " --help"));
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("Exit status: 0"), std::string::npos) << r.out;
  }
  testing::ProcessResult r = runCommand(cli("cache verify --help"));
  EXPECT_NE(r.out.find("2 when problems were found"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace robodiff
