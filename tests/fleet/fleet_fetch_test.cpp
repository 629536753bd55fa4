// A robot host fetches what a build host builds (issue 23): real robodiffd processes with
// their own caches and configuration, DDS on loopback. The values are checked against
// core/dynamics and finite differences, the robot's cache against its index and hashes.
#include <gtest/gtest.h>

#include "fleet/fleet_hosts.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;

std::vector<double> fleetOutputs(const client::Function& f) { return std::vector<double>(f.outputCount()); }

// Evaluates `f` at the reference's state and checks it.
void expectReference(const client::Function& f, const RneaReference& ref) {
  std::vector<double> out = fleetOutputs(f);
  const Status s = f.evaluate({ref.inputs.data(), static_cast<std::size_t>(ref.inputs.size())}, out);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_TRUE(ref.matches(out));
}

TEST(Fleet, BuiltOnceOnTheBuildHostThenServedCompiledByEveryRobot) {
  FleetHosts fleet;
  auto build = fleet.buildHost("fleet_build");
  const Model model = loadUrdfString(arm7Text());
  const RneaReference ref = RneaReference::at(model, 5);
  std::string key;
  {
    auto robot = fleet.robot("robot1", "fleet_build", fleet.publicKey());
    Client c(robotClientOptions());
    client::Function f = c.function(c.loadModel(arm7Text()), kFleetSpec);
    expectReference(f, ref);  // at once: the interpreter serves while the library comes
    ASSERT_TRUE(waitCompiled(c, f.id(), std::chrono::seconds(60))) << robot->log() << build->log();
    expectReference(f, ref);
    const rpc::FleetFigures fleet_figures = c.fleetStatus().fleet;
    EXPECT_EQ(fleet_figures.role, "robot");
    EXPECT_EQ(fleet_figures.artifacts_fetched, 1u);
    EXPECT_EQ(fleet_figures.artifacts_refused, 0u);
    ASSERT_EQ(fleet_figures.peers.size(), 1u);
    EXPECT_EQ(fleet_figures.peers[0].service, "fleet_build");
    EXPECT_TRUE(fleet_figures.peers[0].reachable);
    EXPECT_GT(fleet_figures.peers[0].bytes_fetched, 10000u);
    EXPECT_GT(fleet_figures.peers[0].fetch_seconds, 0.0);
    EXPECT_LT(fleet_figures.peers[0].fetch_seconds, 30.0);
    EXPECT_FALSE(fleet_figures.target.empty());
  }
  // The robot's cache holds one verified entry built for its level, never for `native`.
  const std::vector<cache::Entry> entries = cacheEntries(fleet.robotCache("robot1"));
  ASSERT_EQ(entries.size(), 1u);
  key = entries[0].key;
  EXPECT_NE(entries[0].info.compiler.find(" target=x86-64-v"), std::string::npos) << entries[0].info.compiler;
  EXPECT_TRUE(cache::Cache::open(fleet.robotCache("robot1")).find(key).has_value());  // hashes verified
  // Asked to build once (logged before its BUILDING answer; "fleet_build_done" may come after
  // the robot already has the library, which the worker published).
  EXPECT_EQ(countEvents(build->log(), "fleet_build_requested"), 1u);

  // A second robot: the build host has it and sends it without building again; its
  // clients in local mode load it into their own process.
  auto robot2 = fleet.robot("robot2", "fleet_build", fleet.publicKey());
  Client c2(robotClientOptions());
  client::Function f2 = c2.function(c2.loadModel(arm7Text()), kFleetSpec);
  ASSERT_TRUE(waitCompiled(c2, f2.id(), std::chrono::seconds(30))) << robot2->log();
  EXPECT_EQ(countEvents(build->log(), "fleet_build_requested"), 1u) << "built again";
  EXPECT_EQ(countEvents(build->log(), "fleet_artifact_served"), 2u);
  Client local(robotClientOptions(Mode::Local, fleet.robotCache("robot2")));
  client::Function lf = local.function(local.loadModel(arm7Text()), kFleetSpec);
  EXPECT_EQ(lf.mode(), Mode::Local);
  expectReference(lf, ref);
  EXPECT_EQ(cacheEntries(fleet.robotCache("robot2")).at(0).key, key);
}

TEST(Fleet, AnUntrustedSignatureIsRefusedAndTheInterpreterKeepsServing) {
  FleetHosts fleet;
  auto build = fleet.buildHost("fleet_build_u");
  auto robot = fleet.robot("robot", "fleet_build_u", fleet.strangerKey());
  Client c(robotClientOptions());
  client::Function f = c.function(c.loadModel(arm7Text()), kFleetSpec);
  rpc::FleetFigures last;
  ASSERT_TRUE(waitFleet(c, [](const rpc::FleetFigures& x) { return x.fetch_failures >= 1; },
                        std::chrono::seconds(60), &last))
      << robot->log();
  EXPECT_EQ(last.artifacts_refused, 1u);
  EXPECT_EQ(last.artifacts_fetched, 0u);
  EXPECT_NE(last.peers.at(0).last_problem.find("trusted"), std::string::npos) << last.peers[0].last_problem;
  EXPECT_EQ(countEvents(robot->log(), "fleet_artifact_refused"), 1u);
  for (const rpc::FunctionSummary& s : c.functions()) {
    EXPECT_FALSE(s.compiled);
    EXPECT_NE(s.message.find("no build host delivered"), std::string::npos) << s.message;
  }
  expectReference(f, RneaReference::at(loadUrdfString(arm7Text()), 6));
  EXPECT_TRUE(cacheEntries(fleet.robotCache("robot")).empty());
}

TEST(Fleet, ABuildHostKilledMidTransferIsSurvivedByAskingTheNext) {
  FleetHosts fleet;
  // The first build host serves slowly (16 KiB chunks, 250 ms each): killed mid-transfer.
  auto slow = fleet.buildHost("fleet_slow", {"fleet.chunk_delay=250ms"});
  auto spare = fleet.buildHost("fleet_spare");
  auto robot = fleet.robot("robot", "fleet_slow, fleet_spare", fleet.publicKey(),
                           {"fleet.chunk_size=16KiB", "fleet.call_timeout=1500ms"});
  Client c(robotClientOptions());
  client::Function f = c.function(c.loadModel(arm7Text()), kFleetSpec);
  // The slow host builds it (the spare has nothing either), then starts sending.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (countEvents(slow->log(), "fleet_build_done") == 0 && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // a few chunks in
  slow->kill(std::chrono::milliseconds(0));
  ASSERT_TRUE(waitCompiled(c, f.id(), std::chrono::seconds(60))) << robot->log();
  expectReference(f, RneaReference::at(loadUrdfString(arm7Text()), 7));
  const rpc::FleetFigures figures = c.fleetStatus().fleet;
  ASSERT_EQ(figures.peers.size(), 2u);
  EXPECT_GE(figures.peers[0].failures, 1u);
  EXPECT_NE(figures.peers[0].last_problem.find("lost after"), std::string::npos) << figures.peers[0].last_problem;
  EXPECT_FALSE(figures.peers[0].reachable);
  EXPECT_EQ(figures.peers[1].artifacts_fetched, 1u);
  EXPECT_EQ(countEvents(spare->log(), "fleet_build_requested"), 1u);
  robot.reset();
  // One whole, verified entry; nothing of the broken transfer.
  const std::vector<cache::Entry> entries = cacheEntries(fleet.robotCache("robot"));
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_TRUE(cache::Cache::open(fleet.robotCache("robot")).find(entries[0].key).has_value());
}

}  // namespace
}  // namespace robodiff::testing
