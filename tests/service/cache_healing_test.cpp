// A cached library that goes missing or is damaged between two runs of the service is
// quarantined and built again on the next GetFunction; the function's answers never
// come from the bad file and match the first run's.
#include <sys/stat.h>

#include <fstream>

#include "robodiff/cache/cache.hpp"
#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

namespace fs = std::filesystem;

// The one library.so in the cache (fails the test unless exactly one).
fs::path onlyLibrary(const fs::path& cache_dir) {
  std::vector<fs::path> found;
  for (const auto& e : fs::recursive_directory_iterator(cache_dir / "objects"))
    if (e.path().filename() == "library.so") found.push_back(e.path());
  EXPECT_EQ(found.size(), 1u);
  return found.empty() ? fs::path() : found[0];
}

struct ServiceRun {
  std::vector<double> outputs;
  rpc::HealthReply health;
  std::uint64_t quarantined = 0;  // metrics(): the cache's quarantine/ entries
};

// One service on the workspace's cache: the function compiled (from the cache or built),
// evaluated on `inputs`.
ServiceRun runOnce(ServiceWorkspace& ws, const std::vector<double>& inputs, std::size_t knots) {
  auto service = ws.start(ws.options(true));
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  const rpc::GetFunctionReply f = readyFunction(*service, model.model_id, kRneaJacobianSpec);
  EXPECT_TRUE(waitFor([&] { return summaryOf(*service, f.function_id).compiled; }, std::chrono::seconds(120)))
      << summaryOf(*service, f.function_id).message;
  EXPECT_EQ(inputs.size(), knots * rpc::inputCount(f));
  ServiceRun run;
  run.outputs.resize(knots * rpc::outputCount(f));
  EXPECT_TRUE(service->evaluateBatch(context(), f.function_id, knots, inputs, run.outputs).ok());
  run.health = health(*service);
  run.quarantined = service->metrics().cache_quarantined;
  return run;
}

TEST(CacheHealing, AMissingTruncatedOrReplacedLibraryIsRebuiltOnTheNextGetFunction) {
  ServiceWorkspace ws;
  const std::size_t knots = 50;
  const std::vector<double> inputs = someInputs(knots * 21, 5);  // arm7: q, v, a of 7 each
  const ServiceRun first = runOnce(ws, inputs, knots);
  ASSERT_EQ(first.health.builds_done, 1u);
  EXPECT_EQ(first.quarantined, 0u);

  // Deleted: a miss, built again, the same numbers.
  fs::remove(onlyLibrary(ws.tmp / "cache"));
  const ServiceRun after_delete = runOnce(ws, inputs, knots);
  EXPECT_EQ(after_delete.health.cache_hits, 0u);
  EXPECT_EQ(after_delete.health.cache_misses, 1u);
  EXPECT_EQ(after_delete.health.builds_done, 1u);
  EXPECT_EQ(after_delete.health.builds_failed, 0u);
  EXPECT_TRUE(closeTo(after_delete.outputs, first.outputs, 1e-12));

  // Truncated: the same.
  const fs::path library = onlyLibrary(ws.tmp / "cache");
  ::chmod(library.c_str(), 0700);
  fs::resize_file(library, fs::file_size(library) / 2);
  const ServiceRun after_truncate = runOnce(ws, inputs, knots);
  EXPECT_EQ(after_truncate.health.cache_misses, 1u);
  EXPECT_EQ(after_truncate.health.builds_done, 1u);
  EXPECT_TRUE(closeTo(after_truncate.outputs, first.outputs, 1e-12));
  EXPECT_GT(after_truncate.quarantined, after_delete.quarantined);  // the truncated entry, kept

  // Changed (bytes appended, the size and hash differ): never loaded.
  const fs::path current = onlyLibrary(ws.tmp / "cache");
  ::chmod(current.c_str(), 0700);
  std::ofstream(current, std::ios::app) << "tampered";
  const ServiceRun after_replace = runOnce(ws, inputs, knots);
  EXPECT_EQ(after_replace.health.cache_misses, 1u);
  EXPECT_TRUE(closeTo(after_replace.outputs, first.outputs, 1e-12));
  EXPECT_GT(after_replace.quarantined, after_truncate.quarantined);

  // A run on the healed cache is a plain hit.
  const ServiceRun healed = runOnce(ws, inputs, knots);
  EXPECT_EQ(healed.health.cache_hits, 1u);
  EXPECT_EQ(healed.health.builds_done, 0u);
  EXPECT_FALSE(fs::is_empty(ws.tmp / "cache" / "quarantine"));
  const std::string log = ws.logText();
  EXPECT_NE(log.find("function_compiled"), std::string::npos);
}

// While the service holds the compiled function, its cache entry is lost (the file
// deleted, then quarantined by another process's find()): the held library keeps
// serving, and the next GetFunction of it builds the entry again in the background.
TEST(CacheHealing, AnEntryLostWhileTheServiceHoldsItIsRebuiltOnTheNextGetFunction) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options(true));
  const rpc::LoadModelReply model = loadModel(*service, arm7Urdf());
  const rpc::GetFunctionReply f = readyFunction(*service, model.model_id, kRneaJacobianSpec);
  ASSERT_TRUE(waitFor([&] { return summaryOf(*service, f.function_id).compiled; }, std::chrono::seconds(120)));
  const std::size_t knots = 20;
  const std::vector<double> inputs = someInputs(knots * 21, 7);
  std::vector<double> before(knots * rpc::outputCount(f)), after(before.size());
  ASSERT_TRUE(service->evaluateBatch(context(), f.function_id, knots, inputs, before).ok());

  const fs::path library = onlyLibrary(ws.tmp / "cache");
  const std::string key = library.parent_path().filename().string();
  fs::remove(library);
  {
    cache::Cache other = cache::Cache::open(ws.tmp / "cache");
    EXPECT_FALSE(other.find(key));  // quarantined and unindexed
    EXPECT_FALSE(other.entry(key));
  }
  readyFunction(*service, model.model_id, kRneaJacobianSpec);  // the same function again
  cache::Cache cache = cache::Cache::open(ws.tmp / "cache");
  EXPECT_TRUE(waitFor([&] { return ws.logText().find("cache_entry_rebuilt") != std::string::npos; },
                      std::chrono::seconds(120)))
      << ws.logText();
  EXPECT_NE(ws.logText().find("cache_entry_lost"), std::string::npos);
  EXPECT_TRUE(cache.intact(key));
  EXPECT_TRUE(cache.find(key));
  // Served throughout by the library it held, with the same numbers.
  ASSERT_TRUE(service->evaluateBatch(context(), f.function_id, knots, inputs, after).ok());
  EXPECT_EQ(after, before);
  EXPECT_TRUE(summaryOf(*service, f.function_id).compiled);
}

}  // namespace
}  // namespace robodiff::server::testing
