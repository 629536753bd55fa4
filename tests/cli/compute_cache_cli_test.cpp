// `robodiff compute --backend generated` through the cache, as a user runs it: real
// processes (the CLI, its robodiff-worker, the compiler), a real cache directory with its
// SQLite index. The compiler is a wrapper that logs its command lines, so the tests count
// the builds (one -shared link per build); specs are built at -O0 on arm7 to keep builds short.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "support/cache_workspace.hpp"
#include "support/process.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using nlohmann::json;
using testing::cli;
using testing::runCommand;
using testing::shellQuote;
namespace fs = std::filesystem;

std::string cacheArm7() { return shellQuote((testing::sourceDir() / "examples/robots/arm7.urdf").string()); }

struct ComputeWorkspace : testing::CacheWorkspace {
  // `compute --backend generated` of `spec` at a random state, with this workspace's
  // logging compiler, on its cache unless `extra` has --no-cache.
  testing::ProcessResult compute(const fs::path& spec, const std::string& extra = "") const {
    const bool no_cache = extra.find("--no-cache") != std::string::npos;
    const std::string cache_option = no_cache ? "" : " --cache " + shellQuote(cache.string());
    return runCommand(cli("compute --urdf " + cacheArm7() + " --spec " + shellQuote(spec.string()) +
                          " --derivatives --backend generated --random-state 5 --compiler " + shellQuote(cc.string()) +
                          cache_option + " " + extra));
  }
  // The JSON a successful compute printed.
  json computed(const fs::path& spec, const std::string& extra = "") const {
    const testing::ProcessResult r = compute(spec, extra);
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    return r.exit_code == 0 ? json::parse(r.out) : json::object();
  }
};

// The numbers of a compute output: everything but what it says about the cache.
json numbers(json j) {
  j.erase("cache");
  return j;
}

// Every file under dir with its size and modification time: what "left alone" means.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  if (!fs::exists(dir)) return files;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir)) {
    const std::string size = e.is_regular_file() ? std::to_string(e.file_size()) : "dir";
    files[fs::relative(e.path(), dir).string()] =
        size + " " + std::to_string(e.last_write_time().time_since_epoch().count());
  }
  return files;
}

// The one library.so in the cache's objects.
fs::path onlyLibrary(const fs::path& cache) {
  fs::path found;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(cache / "objects"))
    if (e.path().filename() == "library.so") {
      EXPECT_TRUE(found.empty()) << "more than one library: " << found << ", " << e.path();
      found = e.path();
    }
  return found;
}

TEST(ComputeCacheCli, TheSecondCallLoadsTheCachedLibraryAndGivesTheSameNumbers) {
  ComputeWorkspace w;
  const fs::path spec = w.spec("rnea_jacobian");
  const testing::ProcessResult first = w.compute(spec);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const json built = json::parse(first.out);
  EXPECT_EQ(built["cache"], "built");
  EXPECT_NE(first.err.find("building rnea for arm7 into the cache " + w.cache.string()), std::string::npos)
      << first.err;
  EXPECT_EQ(w.builds(), 1u);
  ASSERT_TRUE(built.contains("jacobian")) << built;

  const testing::ProcessResult second = w.compute(spec);
  ASSERT_EQ(second.exit_code, 0) << second.err;
  const json hit = json::parse(second.out);
  EXPECT_EQ(hit["cache"], "hit");
  EXPECT_EQ(second.err.find("building"), std::string::npos) << second.err;
  EXPECT_EQ(w.builds(), 1u) << "the second call compiled again";
  EXPECT_EQ(numbers(hit).dump(), numbers(built).dump());  // bit for bit: the same library, the same state

  // The table says where the library came from.
  const testing::ProcessResult table = w.compute(spec, "--format table");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("generated backend, from the cache)"), std::string::npos) << table.out;
}

TEST(ComputeCacheCli, FindsWhatWarmupBuiltUnderTheSameKey) {
  ComputeWorkspace w;
  const fs::path spec = w.spec("rnea_jacobian");
  const testing::ProcessResult warmup =
      runCommand(cli("warmup --urdf " + cacheArm7() + " --spec " + shellQuote(spec.string()) + " --cache " +
                     shellQuote(w.cache.string()) + " --compiler " + shellQuote(w.cc.string())));
  ASSERT_EQ(warmup.exit_code, 0) << warmup.out << warmup.err;
  ASSERT_EQ(w.builds(), 1u);
  EXPECT_EQ(w.computed(spec)["cache"], "hit");
  EXPECT_EQ(w.builds(), 1u);
}

TEST(ComputeCacheCli, NoCacheCompilesAndLeavesTheCacheAlone) {
  ComputeWorkspace w;
  const fs::path spec = w.spec("rnea_jacobian");
  // No cache yet: --no-cache compiles (into a temporary directory) and makes none.
  const json uncached = w.computed(spec, "--no-cache");
  EXPECT_EQ(uncached["cache"], "off");
  EXPECT_EQ(w.builds(), 1u);
  EXPECT_FALSE(fs::exists(w.cache));

  // With a cache holding the function: --no-cache compiles again and touches nothing in it.
  const json cached = w.computed(spec);
  ASSERT_EQ(cached["cache"], "built");
  ASSERT_EQ(w.builds(), 2u);
  const std::map<std::string, std::string> before = snapshot(w.cache);
  const json again = w.computed(spec, "--no-cache");
  EXPECT_EQ(again["cache"], "off");
  EXPECT_EQ(w.builds(), 3u);
  EXPECT_EQ(snapshot(w.cache), before);
  EXPECT_EQ(numbers(again).dump(), numbers(cached).dump());

  const testing::ProcessResult both = w.compute(spec, "--no-cache --cache " + shellQuote(w.cache.string()));
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("--cache excludes --no-cache"), std::string::npos) << both.err;
}

TEST(ComputeCacheCli, ACorruptCachedLibraryIsQuarantinedAndRebuiltNotLoaded) {
  ComputeWorkspace w;
  const fs::path spec = w.spec("rnea_jacobian");
  const json built = w.computed(spec);
  ASSERT_EQ(built["cache"], "built");
  // Replace the library by as many bytes of something else: only its SHA-256 tells.
  const fs::path library = onlyLibrary(w.cache);
  ASSERT_FALSE(library.empty());
  const std::uintmax_t size = fs::file_size(library);
  fs::permissions(library, fs::perms::owner_write, fs::perm_options::add);
  std::ofstream(library, std::ios::binary | std::ios::trunc) << std::string(size, '\x7f');
  fs::permissions(library, fs::perms::owner_write, fs::perm_options::remove);

  const testing::ProcessResult r = w.compute(spec);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json rebuilt = json::parse(r.out);
  EXPECT_EQ(rebuilt["cache"], "built");
  EXPECT_EQ(w.builds(), 2u);
  EXPECT_NE(r.err.find("SHA-256 mismatch"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("quarantine"), std::string::npos) << r.err;
  EXPECT_EQ(numbers(rebuilt).dump(), numbers(built).dump());
  std::size_t quarantined = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(w.cache / "quarantine")) quarantined += e.is_directory();
  EXPECT_EQ(quarantined, 1u);
  EXPECT_EQ(w.computed(spec)["cache"], "hit");
  EXPECT_EQ(w.builds(), 2u);
}

TEST(ComputeCacheCli, AUserFunctionIsCachedToo) {
  ComputeWorkspace w;
  const fs::path spec = w.spec("arm7_mpc_knot");
  const json built = w.computed(spec);
  EXPECT_EQ(built["cache"], "built");
  const json hit = w.computed(spec);
  EXPECT_EQ(hit["cache"], "hit");
  EXPECT_EQ(w.builds(), 1u);
  EXPECT_EQ(numbers(hit).dump(), numbers(built).dump());
  EXPECT_TRUE(hit.contains("random_state")) << hit;
}

TEST(ComputeCacheCli, AnUnusableCacheDirectoryIsNamed) {
  ComputeWorkspace w;
  const fs::path not_a_directory = w.tmp.file("plain-file", "x");
  const testing::ProcessResult r =
      runCommand(cli("compute --urdf " + cacheArm7() + " --function gravity --backend generated --random-state 1 --cache " +
                     shellQuote(not_a_directory.string())));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(not_a_directory.string()), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

}  // namespace
}  // namespace robodiff
