// The builder over a real cache directory, a real SQLite index and real robodiff-worker
// processes: a build is published once and found after; a worker killed with SIGKILL
// in the middle of a compile fails only its job, leaves no index row, no file under
// its key and no compiler behind, and the pool builds the next job on a new worker; a
// compiler error reaches the caller with the compiler's message.
#include <signal.h>
#include <sys/types.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <future>
#include <sstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "robodiff/cache/cache.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/worker_pool.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"
#include "worker_fixtures.hpp"

namespace robodiff::workers {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;
using Clock = std::chrono::steady_clock;

// The example spec `name`, built at -O0 for a generic target to keep compiles short.
std::string fastSpec(const TempDir& tmp, const std::string& name) {
  nlohmann::json spec = nlohmann::json::parse(testing::readFile(testing::sourceDir() / "examples/specs" / (name + ".json")));
  spec["build"] = {{"optimization", "O0"}, {"march_native", false}};
  return tmp.file(name + ".json", spec.dump()).string();
}

std::string arm7() { return (testing::sourceDir() / "examples/robots/arm7.urdf").string(); }

// A compiler that answers --version like cc (so keys match cc's) and otherwise runs `body`.
std::string compilerScript(const TempDir& tmp, const std::string& name, const std::string& body) {
  return tmp
      .script(name, "if [ \"$1\" = \"--version\" ] || [ \"$1\" = \"-v\" ]; then exec cc \"$@\"; fi\n" + body)
      .string();
}

WorkerPoolOptions poolOptions(unsigned workers = 1) {
  WorkerPoolOptions o;
  o.worker_executable = testing::workerPath();
  o.workers = workers;
  return o;
}

std::size_t filesUnder(const fs::path& dir) {
  std::size_t n = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file()) ++n;
  return n;
}

TEST(CachedBuilder, BuildsOncePublishesAndThenFindsInTheCache) {
  TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(poolOptions());
  CachedBuilder builder(cache, pool);
  const std::vector<BuildTarget> targets = {{arm7(), false, fastSpec(tmp, "rnea_jacobian"), ""},
                                            {arm7(), false, fastSpec(tmp, "crba"), ""}};
  std::vector<BuildState> seen;
  const std::vector<BuildStatus> first = builder.buildAll(targets, [&](std::size_t i, const BuildStatus& s) {
    if (i == 0) seen.push_back(s.state);
  });
  ASSERT_EQ(first.size(), 2u);
  for (const BuildStatus& s : first) ASSERT_EQ(s.state, BuildState::Done) << s.function << ": " << s.message;
  EXPECT_EQ(first[0].robot, "arm7");
  EXPECT_EQ(seen.back(), BuildState::Done);
  EXPECT_NE(std::find(seen.begin(), seen.end(), BuildState::Building), seen.end());

  const std::optional<cache::Artifact> a = cache.find(first[0].key);
  ASSERT_TRUE(a);
  const codegen::LoadedLibrary lib = codegen::LoadedLibrary::open(a->library());
  EXPECT_NO_THROW(lib.function(first[0].function));

  const std::vector<BuildStatus> second = builder.buildAll(targets);
  for (const BuildStatus& s : second) EXPECT_EQ(s.state, BuildState::Cached) << s.function;
  EXPECT_EQ(second[0].key, first[0].key);
  EXPECT_EQ(pool.stats().succeeded, 2u);  // no job for the cached ones
}

TEST(CachedBuilder, ACachedEntryWhoseLibraryIsGoneIsQuarantinedAndBuiltAgain) {
  TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(poolOptions());
  CachedBuilder builder(cache, pool);
  const std::vector<BuildTarget> targets = {{arm7(), false, fastSpec(tmp, "gravity_jacobian"), ""}};
  const BuildStatus first = builder.buildAll(targets).at(0);
  ASSERT_EQ(first.state, BuildState::Done) << first.message;
  const fs::path library = cache.find(first.key)->library();
  fs::remove(library);

  ::testing::internal::CaptureStderr();
  const BuildStatus again = builder.buildAll(targets).at(0);
  const std::string log = ::testing::internal::GetCapturedStderr();
  ASSERT_EQ(again.state, BuildState::Done) << again.message;  // built again, not "cached", not failed
  EXPECT_NE(log.find("library.so is missing"), std::string::npos) << log;
  EXPECT_EQ(again.key, first.key);
  const std::optional<cache::Artifact> a = cache.find(again.key);
  ASSERT_TRUE(a);
  EXPECT_NO_THROW(codegen::LoadedLibrary::open(a->library()).function(again.function));
  EXPECT_EQ(cache.stats().quarantined, 1u);
}

// The pids the compiler script appended to `log`, one a line; a line still being written is left out.
// (A job's translation units compile two at once, so the script must append, never truncate.)
std::vector<pid_t> compilerPids(const fs::path& log) {
  std::vector<pid_t> pids;
  std::istringstream lines(fs::exists(log) ? testing::readFile(log) : std::string());
  std::string line;
  while (std::getline(lines, line)) {
    if (lines.eof() || line.empty()) break;  // no newline yet: incomplete
    pids.push_back(static_cast<pid_t>(std::strtol(line.c_str(), nullptr, 10)));
  }
  return pids;
}

TEST(CachedBuilder, AWorkerKilledMidCompileFailsOnlyItsJobAndLeavesNothing) {
  TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(poolOptions());
  const fs::path pid_log = tmp / "compilers.pid";
  CachedBuilderOptions options;
  options.compiler = compilerScript(tmp, "slow-cc", "echo $$ >> " + pid_log.string() + "\nexec sleep 60\n");
  options.worker_death_backoff = {};  // no retry: the one death fails the build
  CachedBuilder builder(cache, pool, options);
  const std::vector<BuildTarget> targets = {{arm7(), false, fastSpec(tmp, "rnea_jacobian"), ""}};

  auto running = std::async(std::launch::async, [&] { return builder.buildAll(targets); });
  ASSERT_TRUE(testing::waitFor([&] { return !compilerPids(pid_log).empty(); }, std::chrono::seconds(60)))
      << "the compiler never started";
  const pid_t worker = pool.workers().at(0).pid;
  ASSERT_GT(worker, 0);
  ASSERT_EQ(::kill(worker, SIGKILL), 0);
  ASSERT_EQ(running.wait_for(std::chrono::seconds(30)), std::future_status::ready);
  const std::vector<BuildStatus> result = running.get();

  ASSERT_EQ(result[0].state, BuildState::Failed);
  EXPECT_NE(result[0].message.find("SIGKILL"), std::string::npos) << result[0].message;
  // No row, no artifact, no staging, no compiler left running.
  EXPECT_FALSE(cache.entry(result[0].key));
  EXPECT_FALSE(fs::exists(tmp / "cache" / "objects" / result[0].key.substr(0, 2) / result[0].key));
  EXPECT_EQ(filesUnder(tmp / "cache" / "objects"), 0u);
  EXPECT_EQ(filesUnder(tmp / "cache" / "staging"), 0u);
  for (const pid_t compiler : compilerPids(pid_log))
    EXPECT_TRUE(testing::waitFor([&] { return testing::processIsDead(compiler); }, std::chrono::seconds(10)))
        << "compiler " << compiler << " outlived its worker";

  // The pool replaced the worker; the same key builds with a working compiler.
  EXPECT_TRUE(testing::waitFor([&] { return pool.workers().at(0).pid != worker && pool.workers().at(0).pid > 0; },
                      std::chrono::seconds(10)));
  CachedBuilder working(cache, pool);
  const std::vector<BuildStatus> again = working.buildAll(targets);
  ASSERT_EQ(again[0].state, BuildState::Done) << again[0].message;
  EXPECT_EQ(again[0].key, result[0].key);
  EXPECT_TRUE(cache.find(again[0].key));
}

TEST(CachedBuilder, ACompilerErrorReachesTheCallerAndNothingIsPublished) {
  TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(poolOptions());
  CachedBuilderOptions options;
  options.compiler =
      compilerScript(tmp, "broken-cc", "echo 'part0.c:1:1: error: simulated failure for the test' >&2\nexit 1\n");
  CachedBuilder builder(cache, pool, options);
  const std::vector<BuildStatus> result = builder.buildAll({{arm7(), false, fastSpec(tmp, "gravity_jacobian"), ""}});
  ASSERT_EQ(result[0].state, BuildState::Failed);
  EXPECT_NE(result[0].message.find("simulated failure for the test"), std::string::npos) << result[0].message;
  EXPECT_TRUE(cache.list().empty());
  EXPECT_EQ(filesUnder(tmp / "cache" / "staging"), 0u);
  // A compiler error is the build's own fault: one job, not retried.
  EXPECT_EQ(pool.stats().failed, 1u);
  EXPECT_EQ(pool.stats().crashed, 0u);
}

// Kills the worker running the job each time the compiler script has appended to `log`
// since the last kill (one kill per worker), until `done` is ready; returns how many.
int killWorkerAtEachCompile(WorkerPool& pool, const fs::path& log, std::future<std::vector<BuildStatus>>& done,
                            int at_most) {
  int killed = 0;
  std::uintmax_t log_size_at_kill = 0;
  pid_t last_killed = 0;
  while (done.wait_for(std::chrono::milliseconds(5)) != std::future_status::ready) {
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(log, ec);
    if (killed >= at_most || ec || size <= log_size_at_kill) continue;
    for (const WorkerInfo& w : pool.workers()) {
      if (w.job && w.pid > 0 && w.pid != last_killed && ::kill(w.pid, SIGKILL) == 0) {
        ++killed;
        last_killed = w.pid;
        log_size_at_kill = size;
        break;
      }
    }
  }
  return killed;
}

TEST(CachedBuilder, ABuildWhoseWorkerIsKilledIsRetriedAfterAPauseAndSucceeds) {
  TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(poolOptions());
  const fs::path log = tmp / "compiles.log";
  CachedBuilderOptions options;  // the default pauses: 0.5 s, 2 s
  // The first compile hangs (and is killed with its worker); later ones are cc's.
  options.compiler = compilerScript(tmp, "once-hanging-cc",
                                    "if [ ! -e " + (tmp / "hung").string() + " ]; then touch " + (tmp / "hung").string() +
                                        "; echo $$ >> " + log.string() + "; exec sleep 60; fi\nexec cc \"$@\"\n");
  CachedBuilder builder(cache, pool, options);
  std::vector<std::string> retry_messages;
  const std::vector<BuildTarget> targets = {{arm7(), false, fastSpec(tmp, "rnea_jacobian"), ""}};
  auto done = std::async(std::launch::async, [&] {
    return builder.buildAll(targets, [&](std::size_t, const BuildStatus& s) {
      if (s.state == BuildState::Queued && !s.message.empty()) retry_messages.push_back(s.message);
    });
  });
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(killWorkerAtEachCompile(pool, log, done, 1), 1);
  ::testing::internal::GetCapturedStderr();
  const std::vector<BuildStatus> result = done.get();

  ASSERT_EQ(result[0].state, BuildState::Done) << result[0].message;
  ASSERT_EQ(retry_messages.size(), 1u);
  EXPECT_NE(retry_messages[0].find("SIGKILL"), std::string::npos) << retry_messages[0];
  EXPECT_NE(retry_messages[0].find("trying again in 0.5 s (attempt 2 of 3)"), std::string::npos) << retry_messages[0];
  EXPECT_EQ(pool.stats().crashed, 1u);
  EXPECT_EQ(pool.stats().succeeded, 1u);
  EXPECT_EQ(builder.workerDeathRetries(), 1u);  // what /metrics shows as robodiff_build_retries_total
  const std::optional<cache::Artifact> a = cache.find(result[0].key);
  ASSERT_TRUE(a);
  EXPECT_NO_THROW(codegen::LoadedLibrary::open(a->library()).function(result[0].function));
  EXPECT_EQ(filesUnder(tmp / "cache" / "staging"), 0u);
}

TEST(CachedBuilder, ABuildWhoseWorkerIsKilledEveryTimeFailsAfterThreeAttemptsNamingTheSignal) {
  TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(poolOptions());
  const fs::path log = tmp / "compiles.log";
  CachedBuilderOptions options;
  options.worker_death_backoff = {std::chrono::milliseconds(50), std::chrono::milliseconds(100)};
  options.compiler = compilerScript(tmp, "hanging-cc", "echo $$ >> " + log.string() + "\nexec sleep 60\n");
  CachedBuilder builder(cache, pool, options);
  const std::vector<BuildTarget> targets = {{arm7(), false, fastSpec(tmp, "crba"), ""}};
  auto done = std::async(std::launch::async, [&] { return builder.buildAll(targets); });
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(killWorkerAtEachCompile(pool, log, done, 10), 3);
  const std::string stderr_text = ::testing::internal::GetCapturedStderr();
  const std::vector<BuildStatus> result = done.get();

  ASSERT_EQ(result[0].state, BuildState::Failed);
  EXPECT_NE(result[0].message.find("killed by signal 9 (SIGKILL)"), std::string::npos) << result[0].message;
  EXPECT_NE(result[0].message.find("3 attempts"), std::string::npos) << result[0].message;
  EXPECT_NE(stderr_text.find("attempt 3 of 3"), std::string::npos) << stderr_text;
  EXPECT_EQ(pool.stats().crashed, 3u);
  EXPECT_EQ(builder.workerDeathRetries(), 2u);  // the third death is final
  testing::expectNothingLeft(cache, result[0].key);
}

TEST(CachedBuilder, BadRobotsAndSpecsFailWithTheirReasonWithoutAWorker) {
  TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(poolOptions());
  CachedBuilder builder(cache, pool);
  const std::string bad_urdf = tmp.file("bad.urdf", "<robot name=\"x\"><link name=\"a\"/><joint name=\"j\" type=\"revolute\">"
                                                    "<parent link=\"a\"/><child link=\"missing\"/></joint></robot>")
                                   .string();
  const std::string bad_spec = tmp.file("bad.json", R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["tau"]}]})")
                                   .string();
  const std::vector<BuildStatus> result = builder.buildAll(
      {{bad_urdf, false, fastSpec(tmp, "crba"), ""}, {arm7(), false, bad_spec, ""}, {arm7(), false, (tmp / "none.json").string(), ""}});
  for (const BuildStatus& s : result) EXPECT_EQ(s.state, BuildState::Failed);
  EXPECT_NE(result[0].message.find("bad.urdf"), std::string::npos) << result[0].message;
  EXPECT_NE(result[1].message.find("tau"), std::string::npos) << result[1].message;
  EXPECT_NE(result[2].message.find("none.json"), std::string::npos) << result[2].message;
  EXPECT_EQ(pool.stats().succeeded + pool.stats().failed, 0u);
}

}  // namespace
}  // namespace robodiff::workers
