// Build jobs in this process: a real build published into a real cache and loaded back,
// failures classified and cleaned up, and the JSON that carries requests and outcomes
// between processes. (The key's recipe: tests/cache/prepared_build_test.cpp.)
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/workers/build_job.hpp"
#include "worker_fixtures.hpp"

namespace robodiff::workers {
namespace {

using nlohmann::json;
using testing::TempDir;

// examples/specs/rnea_jacobian.json, built quickly.
std::string rneaJacobianSpec(const std::string& optimization = "O0", bool native = false) {
  json spec = json::parse(testing::readFile(testing::sourceDir() / "examples/specs/rnea_jacobian.json"));
  spec["build"] = {{"optimization", optimization}, {"march_native", native}};
  return spec.dump();
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(BuildJob, ABuildIsPublishedAndLoadsBack) {
  TempDir dir;
  cache::Cache cache = cache::Cache::open(dir / "cache");
  const testing::ClaimedBuild b = testing::claimBuild(cache, testing::arm7Urdf(), rneaJacobianSpec());
  std::vector<std::string> stages;
  const BuildOutcome outcome = executeBuild(b.request, [&](const std::string& s) { stages.push_back(s); });
  ASSERT_TRUE(outcome.ok) << outcome.error_kind << ": " << outcome.message << "\n" << outcome.compiler_output;
  EXPECT_EQ(stages, (std::vector<std::string>{"model", "trace", "compile", "publish"}));
  EXPECT_EQ(outcome.key, b.prepared.key);
  EXPECT_GT(outcome.operations, 0u);
  EXPECT_GT(outcome.library_bytes, 0u);
  EXPECT_GT(outcome.seconds, 0.0);

  const std::optional<cache::Artifact> artifact = cache.find(b.prepared.key);
  ASSERT_TRUE(artifact.has_value()) << "published, but not found";
  const cache::EntryInfo& info = artifact->entry().info;
  EXPECT_EQ(info.robot, "arm7");
  EXPECT_EQ(info.function, "rnea");
  EXPECT_EQ(info.model_hash, b.prepared.info.model_hash);
  EXPECT_GT(info.build_seconds, 0.0);
  const json sizes = json::parse(info.sizes);
  EXPECT_EQ(sizes.at("inputs"), json::parse("[7, 7, 7]"));
  EXPECT_EQ(sizes.at("outputs"), json::parse("[7, 147]"));  // tau, then d tau / d[q v a], 7 x 21

  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(artifact->library());
  codegen::FunctionExpectations expected;
  expected.name = "rnea";
  expected.input_sizes = sizes.at("inputs").get<std::vector<std::uint32_t>>();
  expected.output_sizes = sizes.at("outputs").get<std::vector<std::uint32_t>>();
  EXPECT_NO_THROW(library.function(expected));
  EXPECT_TRUE(std::filesystem::is_empty(cache.dir() / "staging")) << "the build's staging directory is left";
}

// A single-knot build for this CPU is assembly (docs/assembly-backend.md): the entry keeps
// that source, as it keeps a C build's.
TEST(BuildJob, AnAssembledBuildKeepsItsSource) {
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma"))
    GTEST_SKIP() << "the assembly back end needs AVX2 and FMA";
  TempDir dir;
  cache::Cache cache = cache::Cache::open(dir / "cache");
  const std::string spec = R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"batch": false}})";
  const testing::ClaimedBuild b = testing::claimBuild(cache, testing::arm7Urdf(), spec);
  const BuildOutcome outcome = executeBuild(b.request, [](const std::string&) {});
  ASSERT_TRUE(outcome.ok) << outcome.error_kind << ": " << outcome.message << "\n" << outcome.compiler_output;
  const std::optional<cache::Artifact> artifact = cache.find(b.prepared.key);
  ASSERT_TRUE(artifact.has_value());
  EXPECT_TRUE(std::filesystem::exists(artifact->dir() / "src" / "library.s.zst"));
  EXPECT_FALSE(std::filesystem::exists(artifact->dir() / "src" / "library.c.zst"));
}

TEST(BuildJob, ACompilerErrorIsReportedAndLeavesNothing) {
  TempDir dir;
  cache::Cache cache = cache::Cache::open(dir / "cache");
  const testing::ClaimedBuild b = testing::claimBuild(cache, testing::arm7Urdf(), testing::kRneaValueSpec,
                                                      testing::failingCompiler(dir).string());
  const BuildOutcome outcome = executeBuild(b.request);
  EXPECT_FALSE(outcome.ok);
  EXPECT_EQ(outcome.error_kind, "compile_failed") << outcome.message;
  EXPECT_TRUE(contains(outcome.compiler_output, "error: simulated failure")) << outcome.compiler_output;
  EXPECT_TRUE(contains(outcome.message, "error: simulated failure")) << outcome.message;
  EXPECT_TRUE(std::filesystem::is_empty(cache.dir() / "staging")) << "the worker left its staging directory";
  cache.abandon(b.request.claim);  // the requester's part
  testing::expectNothingLeft(cache, b.prepared.key);
}

// Failures before the cache is touched: any claim will do.
BuildRequest unclaimedRequest() {
  BuildRequest r;
  r.urdf = testing::arm7Urdf();
  r.urdf_source = "arm7.urdf";
  r.spec = testing::kRneaValueSpec;
  r.spec_source = "rnea.json";
  r.cache_dir = "/nonexistent/robodiff-cache";
  r.claim = {std::string(64, '0'), "test"};
  return r;
}

TEST(BuildJob, FailuresAreClassified) {
  BuildRequest bad_urdf = unclaimedRequest();
  bad_urdf.urdf = "<robot name='broken'><link name='a'/>";
  BuildOutcome o = executeBuild(bad_urdf);
  EXPECT_EQ(o.error_kind, "invalid_urdf") << o.message;
  EXPECT_TRUE(contains(o.message, "arm7.urdf")) << "the message names the source: " << o.message;

  BuildRequest bad_spec = unclaimedRequest();
  bad_spec.spec = R"({"function": "teleport"})";
  o = executeBuild(bad_spec);
  EXPECT_EQ(o.error_kind, "invalid_spec") << o.message;
  EXPECT_TRUE(contains(o.message, "rnea.json")) << o.message;

  BuildRequest no_compiler = unclaimedRequest();
  no_compiler.compiler = "/nonexistent/cc";
  o = executeBuild(no_compiler);
  EXPECT_EQ(o.error_kind, "compiler_missing") << o.message;

  o = executeBuild(unclaimedRequest());  // the claim is for another key
  EXPECT_FALSE(o.ok);
  EXPECT_EQ(o.error_kind, "internal");
  EXPECT_TRUE(contains(o.message, "disagree")) << o.message;
}

TEST(BuildJob, RequestsRoundTripAsJson) {
  BuildRequest r = unclaimedRequest();
  r.floating_base = true;
  r.function_name = "arm_rnea";
  r.compiler = "gcc";
  r.compiler_memory_limit_bytes = 123456789;
  r.compiler_timeout = std::chrono::milliseconds(4321);
  r.compiler_jobs = 3;
  r.cache_budget_bytes = 987654321;
  r.info.robot = "arm7";
  r.info.sizes = R"({"inputs":[7]})";
  r.info.build_seconds = 1.5;
  r.urdf_limits.max_name_length = 1000;
  r.urdf_limits.max_links = 7;
  const BuildRequest back = buildRequestFromJson(toJson(r));
  EXPECT_EQ(back.urdf, r.urdf);
  EXPECT_EQ(back.urdf_source, r.urdf_source);
  EXPECT_TRUE(back.floating_base);
  EXPECT_EQ(back.spec, r.spec);
  EXPECT_EQ(back.spec_source, r.spec_source);
  EXPECT_EQ(back.function_name, "arm_rnea");
  EXPECT_EQ(back.compiler, "gcc");
  EXPECT_EQ(back.compiler_memory_limit_bytes, 123456789u);
  EXPECT_EQ(back.compiler_timeout, std::chrono::milliseconds(4321));
  EXPECT_EQ(back.compiler_jobs, 3u);
  EXPECT_EQ(back.cache_dir, r.cache_dir);
  EXPECT_EQ(back.cache_budget_bytes, 987654321u);
  EXPECT_EQ(back.claim.key, r.claim.key);
  EXPECT_EQ(back.claim.owner, "test");
  EXPECT_EQ(back.info.robot, "arm7");
  EXPECT_EQ(back.info.sizes, r.info.sizes);
  EXPECT_EQ(back.info.build_seconds, 1.5);
  EXPECT_EQ(back.urdf_limits.max_name_length, 1000u);
  EXPECT_EQ(back.urdf_limits.max_links, 7u);
  EXPECT_EQ(back.urdf_limits.max_depth, UrdfLimits{}.max_depth);
}

// The message of the invalid_argument `f` throws.
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

TEST(BuildJob, MissingOrMistypedFieldsAreNamed) {
  json j = json::parse(toJson(unclaimedRequest()));
  json missing = j;
  missing.erase("urdf");
  EXPECT_TRUE(contains(errorOf([&] { buildRequestFromJson(missing.dump()); }), "missing field \"urdf\""));
  json mistyped = j;
  mistyped["claim"]["key"] = 42;
  const std::string why = errorOf([&] { buildRequestFromJson(mistyped.dump()); });
  EXPECT_TRUE(contains(why, "build request.claim: field \"key\" must be a string")) << why;
  json negative = j;
  negative["compiler_jobs"] = -1;
  EXPECT_TRUE(contains(errorOf([&] { buildRequestFromJson(negative.dump()); }), "\"compiler_jobs\""));
  EXPECT_TRUE(contains(errorOf([&] { buildRequestFromJson("[1, 2]"); }), "expected a JSON object"));
  EXPECT_TRUE(contains(errorOf([&] { buildRequestFromJson("{"); }), "not valid JSON"));
}

TEST(BuildJob, OutcomesRoundTripAsJson) {
  BuildOutcome o;
  o.ok = false;
  o.error_kind = "compile_failed";
  o.message = "the compiler failed";
  o.compiler_output = "error: x";
  o.key = std::string(64, 'a');
  o.seconds = 2.5;
  o.operations = 1234;
  o.library_bytes = 5678;
  const BuildOutcome back = buildOutcomeFromJson(toJson(o));
  EXPECT_FALSE(back.ok);
  EXPECT_EQ(back.error_kind, o.error_kind);
  EXPECT_EQ(back.message, o.message);
  EXPECT_EQ(back.compiler_output, o.compiler_output);
  EXPECT_EQ(back.key, o.key);
  EXPECT_EQ(back.seconds, 2.5);
  EXPECT_EQ(back.operations, 1234u);
  EXPECT_EQ(back.library_bytes, 5678u);
  // A worker's reply carries "id" and "type" besides: they are ignored.
  EXPECT_TRUE(buildOutcomeFromJson(R"({"id": 3, "type": "result", "ok": true})").ok);
  EXPECT_TRUE(contains(errorOf([] { buildOutcomeFromJson(R"({"message": "x"})"); }), "missing field \"ok\""));
}

}  // namespace
}  // namespace robodiff::workers
