// A robot host when no build host answers (issue 23): one that may compile builds the
// library itself; and what `robodiff health` and the target resolution say of a robot.
#include <gtest/gtest.h>

#include "fleet/fleet_hosts.hpp"
#include "robodiff/cache/target_check.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/server/artifact_fetcher.hpp"
#include "support/process.hpp"

namespace robodiff::testing {
namespace {

TEST(FleetFallback, ARobotThatMayCompileBuildsItselfWhenNoBuildHostAnswers) {
  FleetHosts fleet;
  // No --interpreter-only: compiling here is the fallback.
  auto robot = std::make_unique<RobodiffdProcess>(
      fleet.robotCache("robot"), fleet.path() / "robot.log",
      std::vector<std::string>{"--no-iceoryx", "--no-http", "--set", "fleet.role=robot", "--set",
                               "fleet.build_hosts=nobody_here", "--set",
                               "fleet.trusted_keys=" + fleet.publicKey().string(), "--set", "fleet.call_timeout=1s"});
  client::Client c(robotClientOptions());
  client::Function f = c.function(c.loadModel(arm7Text()), kFleetSpec);
  ASSERT_TRUE(waitCompiled(c, f.id(), std::chrono::seconds(90))) << robot->log();
  const RneaReference ref = RneaReference::at(loadUrdfString(arm7Text()), 13);
  std::vector<double> out(f.outputCount());
  ASSERT_TRUE(f.evaluate({ref.inputs.data(), static_cast<std::size_t>(ref.inputs.size())}, out).ok());
  EXPECT_TRUE(ref.matches(out));
  const rpc::FleetFigures figures = c.fleetStatus().fleet;
  EXPECT_EQ(figures.fetch_failures, 1u);
  EXPECT_EQ(figures.artifacts_fetched, 0u);
  EXPECT_FALSE(figures.peers.at(0).reachable);
  const nlohmann::json failed = logEvent(robot->log(), "fetch_failed");
  ASSERT_FALSE(failed.is_null()) << robot->log();
  EXPECT_EQ(failed["next"], "building it here");
  EXPECT_NE(failed["message"].get<std::string>().find("nobody_here"), std::string::npos) << failed.dump();
  EXPECT_EQ(countEvents(robot->log(), "function_compiled"), 1u);

  // What an operator sees.
  const ProcessResult health =
      runCommand(shellQuote(cliPath().string()) + " health --server dds:" + std::to_string(testDomain()));
  ASSERT_EQ(health.exit_code, 0) << health.err;
  EXPECT_NE(health.out.find("role robot"), std::string::npos) << health.out;
  EXPECT_NE(health.out.find("nobody_here"), std::string::npos) << health.out;
  EXPECT_NE(health.out.find("1 fetches failed"), std::string::npos) << health.out;
}

TEST(FleetTarget, AutoIsTheHighestLevelThisCpuRunsAndOthersAreChecked) {
  std::string highest;
  for (const char* level : kTargetLevels)
    if (cache::cpuSupportsLevel(level)) highest = level;
  if (highest.empty()) GTEST_SKIP() << "this CPU supports no x86-64 level beyond the baseline";
  EXPECT_EQ(server::resolveFleetTarget("auto"), highest);
  EXPECT_EQ(server::resolveFleetTarget("x86-64-v2"), "x86-64-v2");
  try {
    server::resolveFleetTarget("x86-64-v9");
    ADD_FAILURE() << "x86-64-v9 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("x86-64-v4"), std::string::npos) << e.what();
  }
  for (const char* level : kTargetLevels)
    if (!cache::cpuSupportsLevel(level))
      EXPECT_THROW(server::resolveFleetTarget(level), std::invalid_argument) << level;
}

}  // namespace
}  // namespace robodiff::testing

namespace robodiff::testing {
namespace {

// robodiffd with `sets` (--set each) on an empty cache: its exit code and log.
ProcessResult robodiffdWith(const std::filesystem::path& dir, const std::vector<std::string>& sets) {
  std::string command = "timeout 20 " + shellQuote(robodiffdPath().string()) +
                        " --no-iceoryx --no-http --dds-domain " + std::to_string(testDomain()) + " --cache " +
                        shellQuote((dir / "cache").string());
  for (const std::string& s : sets) command += " --set " + shellQuote(s);
  return runCommand(command);
}

TEST(FleetSettings, ARoleWithoutWhatItNeedsIsRefusedAtStartNamingTheKey) {
  FleetHosts fleet;
  ProcessResult r = robodiffdWith(fleet.path(), {"fleet.role=build"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("fleet.signing_key"), std::string::npos) << r.err;
  r = robodiffdWith(fleet.path(), {"fleet.role=robot", "fleet.build_hosts=somewhere"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("fleet.trusted_keys"), std::string::npos) << r.err;
  r = robodiffdWith(fleet.path(), {"fleet.role=robot", "fleet.trusted_keys=" + fleet.publicKey().string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("fleet.build_hosts"), std::string::npos) << r.err;
  r = robodiffdWith(fleet.path(), {"fleet.role=robot", "fleet.build_hosts=a-b"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("not a DDS service name"), std::string::npos) << r.err;
  // A signing key others may read is refused, naming the file and the fix.
  std::filesystem::permissions(fleet.signingKey(), std::filesystem::perms::group_read,
                               std::filesystem::perm_options::add);
  r = robodiffdWith(fleet.path(), {"fleet.role=build", "fleet.signing_key=" + fleet.signingKey().string()});
  EXPECT_NE(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(fleet.signingKey().string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("chmod"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace robodiff::testing
