// The cache on a real directory and a real SQLite file: claims, publishing, verification
// before every load, quarantine, budgets and eviction, permissions, and several
// processes (fork) sharing one cache. Artifacts here are made-up files: the cache never
// loads them, it only stores, hashes and hands out paths.
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/model/canonical.hpp"
#include "support/process.hpp"
#include "cache/cache_fixtures.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::cache {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// Made-up build output: a "library" of `bytes` bytes, a description and one source.
ArtifactFiles makeFiles(const TempDir& tmp, const std::string& name, std::size_t bytes) {
  std::string library(bytes, '\0');
  for (std::size_t i = 0; i < bytes; ++i) library[i] = static_cast<char>((i * 131 + name.size()) & 0xff);
  ArtifactFiles f;
  f.library = tmp.file(name + ".so", library);
  f.description = tmp.file(name + ".json", R"({"name":")" + name + R"("})");
  f.sources = {tmp.file(name + "_part0.c", "/* generated */ double f(double x) { return x * x; }\n")};
  return f;
}

Artifact build(Cache& cache, const TempDir& tmp, const std::string& name, std::size_t bytes = 4096) {
  ClaimResult r = cache.claim(keyOf(name), infoFor(name));
  EXPECT_EQ(r.state, ClaimResult::State::Claimed);
  return cache.publish(*r.claim, infoFor(name), makeFiles(tmp, name, bytes));
}

unsigned modeOf(const fs::path& p) {
  struct stat st {};
  EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
  return st.st_mode & 07777u;
}

void flipByte(const fs::path& file, std::size_t offset) {
  ::chmod(file.c_str(), 0700);
  std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
  f.seekg(static_cast<std::streamoff>(offset));
  char c = 0;
  f.read(&c, 1);
  c = static_cast<char>(c ^ 0x01);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(&c, 1);
}

std::size_t countFiles(const fs::path& dir) {
  std::size_t n = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file()) ++n;
  return n;
}

TEST(CacheKey, EveryFieldChangesTheKeyAndNothingElseDoes) {
  BuildIdentity a{"m", "{}", "gen 1", "cc 12", {"-O2", "-march=native"}, "x86_64 native; flags avx2"};
  const std::string base = a.key();
  EXPECT_TRUE(isCacheKey(base));
  EXPECT_EQ(BuildIdentity(a).key(), base);
  auto changed = [&](auto mutate) {
    BuildIdentity b = a;
    mutate(b);
    return b.key();
  };
  EXPECT_NE(changed([](BuildIdentity& b) { b.model_hash = "m2"; }), base);
  EXPECT_NE(changed([](BuildIdentity& b) { b.spec = "{ }"; }), base);
  EXPECT_NE(changed([](BuildIdentity& b) { b.generator = "gen 2"; }), base);
  EXPECT_NE(changed([](BuildIdentity& b) { b.compiler = "cc 13"; }), base);
  EXPECT_NE(changed([](BuildIdentity& b) { b.flags = {"-O3", "-march=native"}; }), base);
  EXPECT_NE(changed([](BuildIdentity& b) { b.target_cpu = "x86_64 generic"; }), base);
  // A newline cannot make one field's value pass for another field.
  EXPECT_NE(changed([](BuildIdentity& b) {
              b.model_hash = "m\nspec={}";
              b.spec = "";
            }),
            base);
}

TEST(CacheKey, NativeTargetsNameTheCpuGenericOnesOnlyTheArchitecture) {
  const std::string generic = targetCpuIdentity(false);
  const std::string native = targetCpuIdentity(true);
  EXPECT_NE(generic, native);
  EXPECT_NE(native.find("flags"), std::string::npos) << native;
  // The instruction cache decides which functions are addressed compactly.
  EXPECT_NE(native.find("l1i " + std::to_string(codegen::hostInstructionCacheBytes()) + " bytes"), std::string::npos)
      << native;
  EXPECT_EQ(native, targetCpuIdentity(true));
  EXPECT_FALSE(isCacheKey("ABC"));
  EXPECT_FALSE(isCacheKey(std::string(64, 'g')));
}

TEST(Cache, CreatesAPrivateDirectoryWithAWalIndex) {
  TempDir tmp;
  const fs::path dir = tmp / "nested" / "cache";
  Cache cache = Cache::open(dir);
  EXPECT_EQ(modeOf(dir), 0700u);
  EXPECT_EQ(modeOf(dir / "objects"), 0700u);
  EXPECT_EQ(modeOf(dir / "index.sqlite"), 0600u);
  build(cache, tmp, "rnea");
  const testing::ProcessResult r =
      testing::runCommand("sqlite3 " + testing::shellQuote((dir / "index.sqlite").string()) + " 'PRAGMA journal_mode'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "wal\n");
}

TEST(Cache, PublishedArtifactsAreFoundVerifiedAndCounted) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  const std::string key = keyOf("rnea");
  EXPECT_FALSE(cache.find(key));
  const Artifact published = build(cache, tmp, "rnea", 10000);
  EXPECT_EQ(published.key(), key);
  EXPECT_EQ(published.entry().state, "ready");
  EXPECT_EQ(published.entry().library_bytes, 10000u);
  EXPECT_EQ(testing::readFile(published.library()), testing::readFile(tmp / "rnea.so"));
  EXPECT_EQ(published.entry().library_sha256, sha256Hex(testing::readFile(tmp / "rnea.so")));
  EXPECT_EQ(testing::readFile(published.description()), R"({"name":"rnea"})");
  // The source is kept zstd-compressed (frame magic 28 b5 2f fd).
  const std::string packed = testing::readFile(published.dir() / "src" / "rnea_part0.c.zst");
  ASSERT_GE(packed.size(), 4u);
  EXPECT_EQ(packed.substr(0, 4), std::string("\x28\xb5\x2f\xfd"));
  EXPECT_EQ(published.entry().info.robot, "arm7");
  EXPECT_EQ(published.entry().info.sizes, infoFor("rnea").sizes);

  const std::optional<Artifact> again = cache.find(key);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->dir(), published.dir());
  EXPECT_EQ(cache.entry(key)->hits, 1u);  // this one; publishing is not a hit
  // A claim of a ready key hands out the artifact instead.
  ClaimResult r = cache.claim(key, infoFor("rnea"));
  EXPECT_EQ(r.state, ClaimResult::State::Ready);
  ASSERT_TRUE(r.artifact);
  // Nothing is left in staging.
  EXPECT_EQ(countFiles(tmp / "cache" / "staging"), 0u);
}

TEST(Cache, AClaimIsExclusiveUntilPublishedOrAbandoned) {
  TempDir tmp;
  Cache first = Cache::open(tmp / "cache");
  Cache second = Cache::open(tmp / "cache");  // another connection, as another process has
  const std::string key = keyOf("aba");
  ClaimResult a = first.claim(key, infoFor("aba"));
  ASSERT_EQ(a.state, ClaimResult::State::Claimed);
  ClaimResult b = second.claim(key, infoFor("aba"));
  EXPECT_EQ(b.state, ClaimResult::State::Busy);
  EXPECT_EQ(b.holder, a.claim->owner);
  EXPECT_FALSE(second.find(key));  // building is not ready

  const fs::path staging = first.stagingDir(*a.claim);
  std::ofstream(staging / "partial.o") << "half a build";
  first.abandon(*a.claim);
  EXPECT_FALSE(first.entry(key));
  EXPECT_FALSE(fs::exists(staging));
  ClaimResult c = second.claim(key, infoFor("aba"));
  EXPECT_EQ(c.state, ClaimResult::State::Claimed);
}

TEST(Cache, AnExpiredLeaseIsTakenOverAndTheOldOwnerLearnsIt) {
  TempDir tmp;
  CacheOptions options;
  options.lease = std::chrono::milliseconds(150);
  Cache first = Cache::open(tmp / "cache", options);
  Cache second = Cache::open(tmp / "cache", options);
  const std::string key = keyOf("crba");
  ClaimResult a = first.claim(key, infoFor("crba"));
  ASSERT_EQ(a.state, ClaimResult::State::Claimed);
  first.renew(*a.claim);
  EXPECT_EQ(second.claim(key, infoFor("crba")).state, ClaimResult::State::Busy);
  ClaimResult b = second.waitOrClaim(key, infoFor("crba"), std::chrono::steady_clock::now() + std::chrono::seconds(5));
  ASSERT_EQ(b.state, ClaimResult::State::Claimed);
  EXPECT_NE(b.claim->owner, a.claim->owner);
  try {
    first.renew(*a.claim);
    FAIL() << "renewing a lost claim must throw";
  } catch (const CacheError& e) {
    EXPECT_EQ(e.kind(), CacheError::Kind::ClaimLost);
  }
  // Abandoning a lost claim does not drop the new owner's.
  first.abandon(*a.claim);
  EXPECT_EQ(second.entry(key)->owner, b.claim->owner);
}

TEST(Cache, AClaimOfADeadProcessIsTakenOverAtOnce) {
  TempDir tmp;
  const std::string key = keyOf("gravity");
  const pid_t child = fork();
  if (child == 0) {
    // Claims with a long lease, then dies without releasing it.
    try {
      Cache cache = Cache::open(tmp / "cache");
      ClaimResult r = cache.claim(key, infoFor("gravity"));
      cache.stagingDir(*r.claim);
      _exit(r.state == ClaimResult::State::Claimed ? 0 : 3);
    } catch (...) {
      _exit(4);
    }
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  Cache cache = Cache::open(tmp / "cache");
  ASSERT_EQ(cache.entry(key)->state, "building");
  EXPECT_EQ(cache.claim(key, infoFor("gravity")).state, ClaimResult::State::Claimed);
}

TEST(Cache, GcRemovesClaimsAndStagingLeftByDeadProcesses) {
  TempDir tmp;
  const pid_t child = fork();
  if (child == 0) {
    try {
      Cache cache = Cache::open(tmp / "cache");
      ClaimResult r = cache.claim(keyOf("nle"), infoFor("nle"));
      std::ofstream(cache.stagingDir(*r.claim) / "part.o") << "x";
      _exit(0);
    } catch (...) {
      _exit(4);
    }
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  Cache cache = Cache::open(tmp / "cache");
  ClaimResult mine = cache.claim(keyOf("fk"), infoFor("fk"));  // alive: kept
  cache.stagingDir(*mine.claim);
  const GcReport report = cache.gc();
  EXPECT_EQ(report.stale_claims, 1u);
  EXPECT_EQ(report.stale_staging, 1u);
  EXPECT_FALSE(cache.entry(keyOf("nle")));
  EXPECT_TRUE(cache.entry(keyOf("fk")));
  EXPECT_TRUE(fs::exists(tmp / "cache" / "staging" / (keyOf("fk") + "@" + mine.claim->owner)));
}

TEST(Cache, AFlippedByteIsQuarantinedNeverHandedOutAndRebuilt) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  const fs::path library = build(cache, tmp, "minv").library();
  flipByte(library, 100);
  ::testing::internal::CaptureStderr();
  EXPECT_FALSE(cache.find(keyOf("minv")));
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("SHA-256 mismatch"), std::string::npos) << log;
  EXPECT_NE(log.find("quarantine"), std::string::npos) << log;
  EXPECT_FALSE(cache.entry(keyOf("minv")));
  EXPECT_FALSE(fs::exists(library));
  EXPECT_EQ(cache.stats().quarantined, 1u);
  // The next use builds it again.
  const Artifact rebuilt = build(cache, tmp, "minv");
  EXPECT_EQ(testing::readFile(rebuilt.library()), testing::readFile(tmp / "minv.so"));
}

TEST(Cache, VerifyReportsTruncatedAndCorruptArtifacts) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  const fs::path a = build(cache, tmp, "a").library();
  const fs::path b = build(cache, tmp, "b").library();
  build(cache, tmp, "c");
  ::chmod(a.c_str(), 0700);
  fs::resize_file(a, 1000);
  flipByte(b, 7);
  ::testing::internal::CaptureStderr();
  const VerifyReport report = cache.verify();
  ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(report.checked, 3u);
  ASSERT_EQ(report.problems.size(), 2u);
  std::set<std::string> keys;
  for (const VerifyProblem& p : report.problems) keys.insert(p.key);
  EXPECT_EQ(keys, (std::set<std::string>{keyOf("a"), keyOf("b")}));
  for (const VerifyProblem& p : report.problems) {
    if (p.key == keyOf("a")) {
      EXPECT_NE(p.problem.find("truncated"), std::string::npos) << p.problem;
    }
    if (p.key == keyOf("b")) {
      EXPECT_NE(p.problem.find("SHA-256 mismatch"), std::string::npos) << p.problem;
    }
  }
  EXPECT_EQ(cache.verify().problems.size(), 0u);
  EXPECT_EQ(cache.list().size(), 1u);
}

TEST(Cache, RefusesDirectoriesOthersCanWriteOrItCannot) {
  TempDir tmp;
  auto refusal = [](const fs::path& dir) -> std::string {
    try {
      Cache::open(dir);
    } catch (const CacheError& e) {
      EXPECT_EQ(e.kind(), CacheError::Kind::Permissions);
      return e.what();
    }
    return "(opened)";
  };
  fs::create_directory(tmp / "shared");
  ::chmod((tmp / "shared").c_str(), 0777);
  const std::string shared = refusal(tmp / "shared");
  EXPECT_NE(shared.find("0777"), std::string::npos) << shared;
  EXPECT_NE(shared.find("other users"), std::string::npos) << shared;

  fs::create_directory(tmp / "readonly");
  ::chmod((tmp / "readonly").c_str(), 0500);
  const std::string readonly = refusal(tmp / "readonly");
  EXPECT_NE(readonly.find("not writable"), std::string::npos) << readonly;

  tmp.file("plain-file", "x");
  const std::string under_file = refusal(tmp / "plain-file" / "cache");
  EXPECT_NE(under_file.find((tmp / "plain-file").string()), std::string::npos) << under_file;

  // An artifact made group-writable after publishing is not loaded.
  Cache cache = Cache::open(tmp / "cache");
  const fs::path library = build(cache, tmp, "rnea").library();
  ::chmod(library.c_str(), 0775);
  try {
    cache.find(keyOf("rnea"));
    FAIL() << "a group-writable library must be refused";
  } catch (const CacheError& e) {
    EXPECT_EQ(e.kind(), CacheError::Kind::Permissions);
    EXPECT_NE(std::string(e.what()).find("0775"), std::string::npos) << e.what();
  }
}

TEST(Cache, EvictionKeepsTheBudgetLeastRecentlyUsedFirstAndSparesEntriesInUse) {
  TempDir tmp;
  CacheOptions options;
  options.budget_bytes = 3 * 20000 + 2000;  // room for three 20 kB libraries and their extras
  Cache cache = Cache::open(tmp / "cache", options);
  std::optional<Artifact> held = build(cache, tmp, "e0", 20000);  // oldest, but in use
  build(cache, tmp, "e1", 20000);
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // last_used has 1 s resolution
  build(cache, tmp, "e2", 20000);
  build(cache, tmp, "e3", 20000);
  std::set<std::string> keys;
  std::uint64_t total = 0;
  for (const Entry& e : cache.list()) {
    keys.insert(e.key);
    total += e.total_bytes;
  }
  EXPECT_LE(total, options.budget_bytes);
  EXPECT_EQ(keys, (std::set<std::string>{keyOf("e0"), keyOf("e2"), keyOf("e3")}));
  EXPECT_EQ(countFiles(tmp / "cache" / "staging"), 0u);
  // Nothing can go while everything left is in use: a new entry is refused, cleanly.
  std::optional<Artifact> h2 = cache.find(keyOf("e2")), h3 = cache.find(keyOf("e3"));
  ClaimResult r = cache.claim(keyOf("e4"), infoFor("e4"));
  try {
    cache.publish(*r.claim, infoFor("e4"), makeFiles(tmp, "e4", 20000));
    FAIL() << "a full budget must be reported";
  } catch (const CacheError& e) {
    EXPECT_EQ(e.kind(), CacheError::Kind::Budget);
    EXPECT_NE(std::string(e.what()).find("in use"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(cache.entry(keyOf("e4")));
  EXPECT_FALSE(fs::exists(tmp / "cache" / "objects" / keyOf("e4").substr(0, 2) / keyOf("e4")));
  EXPECT_EQ(countFiles(tmp / "cache" / "staging"), 0u);
  // Released: gc to a tiny budget takes them all.
  held.reset();
  h2.reset();
  h3.reset();
  const GcReport report = cache.gc(1);
  EXPECT_EQ(report.evicted.size(), 3u);
  EXPECT_EQ(report.bytes_after, 0u);
  EXPECT_TRUE(cache.list().empty());
}

TEST(Cache, RemoveRefusesAnEntryInUse) {
  TempDir tmp;
  Cache cache = Cache::open(tmp / "cache");
  std::optional<Artifact> held = build(cache, tmp, "x");
  EXPECT_THROW(cache.remove(keyOf("x")), CacheError);
  held.reset();
  EXPECT_TRUE(cache.remove(keyOf("x")));
  EXPECT_FALSE(cache.remove(keyOf("x")));
  EXPECT_EQ(countFiles(tmp / "cache" / "objects"), 0u);
}

// Several processes want the same keys at once: each key is built exactly once, and every
// process ends with the same verified artifact.
TEST(Cache, ConcurrentProcessesBuildEachKeyOnce) {
  TempDir tmp;
  const fs::path log = tmp / "builds.log";
  const int processes = 4;
  const std::vector<std::string> names = {"k0", "k1", "k2", "k3", "k4"};
  std::vector<pid_t> children;
  for (int p = 0; p < processes; ++p) {
    const pid_t child = fork();
    if (child == 0) {
      try {
        Cache cache = Cache::open(tmp / "cache");
        for (const std::string& name : names) {
          ClaimResult r = cache.waitOrClaim(keyOf(name), infoFor(name),
                                            std::chrono::steady_clock::now() + std::chrono::seconds(30));
          if (r.state == ClaimResult::State::Claimed) {
            const int fd = ::open(log.c_str(), O_WRONLY | O_APPEND | O_CREAT, 0600);
            const std::string line = name + "\n";
            if (::write(fd, line.data(), line.size()) < 0) _exit(5);
            ::close(fd);
            std::this_thread::sleep_for(std::chrono::milliseconds(30));  // a build takes time
            cache.publish(*r.claim, infoFor(name), makeFiles(tmp, name + "_" + std::to_string(p), 5000));
          } else if (r.state != ClaimResult::State::Ready) {
            _exit(6);
          }
        }
        _exit(0);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "child: %s\n", e.what());
        _exit(7);
      }
    }
    children.push_back(child);
  }
  for (pid_t c : children) {
    int status = 0;
    ASSERT_EQ(waitpid(c, &status, 0), c);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child exit status " << status;
  }
  std::ifstream in(log);
  std::multiset<std::string> built;
  for (std::string line; std::getline(in, line);) built.insert(line);
  EXPECT_EQ(built.size(), names.size());
  for (const std::string& name : names) EXPECT_EQ(built.count(name), 1u) << name;
  Cache cache = Cache::open(tmp / "cache");
  EXPECT_TRUE(cache.verify().problems.empty());
  EXPECT_EQ(cache.list().size(), names.size());
}

}  // namespace
}  // namespace robodiff::cache
