// The URDF limits a requester reads a robot under travel with its builds: a robot that a
// server accepted under raised limits (here a 300-character link name, over the default
// max_name_length of 256) is built by a real worker, which would refuse it under its own
// defaults; without the raised limits the build is refused naming the limit.
#include <gtest/gtest.h>

#include <regex>

#include "robodiff/cache/cache.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/worker_pool.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"
#include "worker_fixtures.hpp"

namespace robodiff::workers {
namespace {

// arm7 with link3 renamed to a 300-character name.
std::string arm7WithALongLinkName() {
  const std::string urdf = std::regex_replace(testing::arm7Urdf(), std::regex("\"link3\""),
                                              "\"" + std::string(300, 'l') + "\"");
  EXPECT_NE(urdf, testing::arm7Urdf());
  return urdf;
}

BuildStatus buildUnder(const UrdfLimits& limits, const testing::TempDir& tmp) {
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPoolOptions pool_options;
  pool_options.worker_executable = testing::workerPath();
  pool_options.workers = 1;
  WorkerPool pool(pool_options);
  CachedBuilderOptions options;
  options.urdf_limits = limits;
  CachedBuilder builder(cache, pool, options);
  BuildTarget target{"long_names.urdf", false, "<spec>", ""};
  target.urdf_text = arm7WithALongLinkName();
  target.spec_text = testing::kRneaValueSpec;
  return builder.buildAll({target}).at(0);
}

TEST(UrdfLimitsOfABuild, RaisedLimitsReachTheWorker) {
  testing::TempDir tmp;
  UrdfLimits raised;
  raised.max_name_length = 1000;
  const BuildStatus done = buildUnder(raised, tmp);
  EXPECT_EQ(done.state, BuildState::Done) << done.message;
}

TEST(UrdfLimitsOfABuild, DefaultLimitsRefuseTheRobotNamingTheLimit) {
  testing::TempDir tmp;
  const BuildStatus done = buildUnder(UrdfLimits{}, tmp);
  EXPECT_EQ(done.state, BuildState::Failed);
  EXPECT_NE(done.message.find("max_name_length"), std::string::npos) << done.message;
}

// The worker applies the request's limits itself (it does not trust that the requester
// checked): a request under lowered limits is refused by executeBuild.
TEST(UrdfLimitsOfABuild, TheWorkerAppliesTheRequestsLimits) {
  testing::TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  testing::ClaimedBuild b = testing::claimBuild(cache, testing::arm7Urdf(), testing::kRneaValueSpec);
  b.request.urdf_limits.max_links = 3;
  const BuildOutcome outcome = executeBuild(b.request);
  EXPECT_FALSE(outcome.ok);
  EXPECT_EQ(outcome.error_kind, "invalid_urdf") << outcome.message;
  EXPECT_NE(outcome.message.find("max_links"), std::string::npos) << outcome.message;
}

}  // namespace
}  // namespace robodiff::workers
