// A caller that has the robot parsed and hashed already (robodiffd, at LoadModel) hands
// both to the builder, which then neither reads, parses nor hashes the URDF again: the
// key is the one prepared from the given hash, and the worker (another process, which
// parses the text once more) builds under it. Real cache, real SQLite, a real worker.
#include <gtest/gtest.h>

#include <memory>

#include <nlohmann/json.hpp>

#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/worker_pool.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"
#include "worker_fixtures.hpp"

namespace robodiff::workers {
namespace {

struct ParsedArm {
  std::string urdf = testing::arm7Urdf();
  std::shared_ptr<const Model> model =
      std::make_shared<const Model>(loadUrdfString(urdf, RootJoint::Fixed, "arm7.urdf"));
  std::string hash = canonicalHash(*model);
};

// A target naming a URDF path that does not exist: only the given text and model serve.
BuildTarget parsedTarget(const ParsedArm& arm, const std::string& hash) {
  BuildTarget t{"/nonexistent/arm7.urdf", false, "<spec>", ""};
  t.urdf_text = arm.urdf;
  t.spec_text = testing::kRneaValueSpec;
  t.model = arm.model;
  t.model_hash = hash;
  return t;
}

WorkerPoolOptions onePool() {
  WorkerPoolOptions o;
  o.worker_executable = testing::workerPath();
  o.workers = 1;
  return o;
}

TEST(ParsedTarget, IsBuiltUnderTheKeyOfTheGivenHashWithoutReadingTheUrdfPath) {
  testing::TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(onePool());
  CachedBuilder builder(cache, pool);
  const ParsedArm arm;
  const BuildStatus done = builder.buildAll({parsedTarget(arm, arm.hash)}).at(0);
  ASSERT_EQ(done.state, BuildState::Done) << done.message;
  const std::string expected =
      cache::prepareBuild(*arm.model, arm.hash, parseFunctionSpec(testing::kRneaValueSpec), "", "").key;
  EXPECT_EQ(done.key, expected);
  EXPECT_EQ(done.robot, "arm7");
  ASSERT_TRUE(cache.find(done.key));
  EXPECT_EQ(cache.entry(done.key)->info.model_hash, arm.hash);
}

// The given hash is used as it is (not computed again here): a wrong one gives a key the
// worker, hashing the text itself, refuses to build under; nothing is published.
TEST(ParsedTarget, AWrongHashIsCaughtByTheWorkerAndNothingIsPublished) {
  testing::TempDir tmp;
  cache::Cache cache = cache::Cache::open(tmp / "cache");
  WorkerPool pool(onePool());
  CachedBuilder builder(cache, pool);
  const ParsedArm arm;
  const std::string wrong(64, 'a');
  const BuildStatus done = builder.buildAll({parsedTarget(arm, wrong)}).at(0);
  EXPECT_EQ(done.state, BuildState::Failed);
  EXPECT_EQ(done.key, cache::prepareBuild(*arm.model, wrong, parseFunctionSpec(testing::kRneaValueSpec), "", "").key);
  EXPECT_NE(done.message.find("disagree on the build's identity"), std::string::npos) << done.message;
  EXPECT_FALSE(cache.find(done.key));
}

}  // namespace
}  // namespace robodiff::workers
