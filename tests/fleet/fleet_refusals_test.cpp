// What a robot host does with a build host that lies (issue 23): each spoiled artifact is
// refused before anything reaches the robot's cache, counted and logged, and the robot's
// interpreter keeps serving right values. The build host runs in this process (a real
// Service and DdsServer behind faulty_build_host.hpp); the robot is a real robodiffd.
#include <cstdio>

#include <gtest/gtest.h>

#include "fleet/faulty_build_host.hpp"
#include "fleet/fleet_hosts.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::testing {
namespace {

// A build host in this process whose artifact answers can be spoiled.
class InProcessBuildHost {
 public:
  InProcessBuildHost(FleetHosts& fleet, const std::string& service)
      : log_(std::fopen((fleet.path() / (service + ".log")).c_str(), "w")),
        logger_(log_),
        key_(cache::SigningKey::load(fleet.signingKey())) {
    server::ServiceOptions options;
    options.cache_dir = fleet.path() / (service + "-cache");
    options.job_workers = 0;
    options.worker_executable = workerPath().string();
    options.artifact_serving.enabled = true;
    options.artifact_serving.signing_key = fleet.signingKey();
    service_ = std::make_unique<server::Service>(options, logger_);
    faulty_ = std::make_unique<FaultyArtifacts>(*service_, key_);
    server::DdsServerOptions dds;
    dds.domain_id = static_cast<std::uint32_t>(testDomain());
    dds.service_name = service;
    server_ = std::make_unique<server::DdsServer>(*faulty_, dds, logger_);
    server_->start();
    service_->markServing();
  }
  ~InProcessBuildHost() {
    server_.reset();
    faulty_.reset();
    service_.reset();
    std::fclose(log_);
  }
  void spoil(ArtifactFault fault) { faulty_->set(fault); }

 private:
  std::FILE* log_;
  server::Logger logger_;
  cache::SigningKey key_;
  std::unique_ptr<server::Service> service_;
  std::unique_ptr<FaultyArtifacts> faulty_;
  std::unique_ptr<server::DdsServer> server_;
};

struct RefusalCase {
  ArtifactFault fault;
  const char* says;  // in the robot's last problem
};

TEST(FleetRefusals, EverySpoiledArtifactIsRefusedAndNothingReachesTheCache) {
  useLoopbackDds();
  FleetHosts fleet;
  InProcessBuildHost host(fleet, "fleet_liar");
  const RneaReference ref = RneaReference::at(loadUrdfString(arm7Text()), 9);
  const RefusalCase cases[] = {
      {ArtifactFault::FlippedByte, "SHA-256"},
      {ArtifactFault::OtherTarget, "another target"},
      {ArtifactFault::OtherFunction, "portable key"},
      {ArtifactFault::ShortChunk, "disagrees with the manifest"},
  };
  int round = 0;
  for (const RefusalCase& c : cases) {
    SCOPED_TRACE(c.says);
    host.spoil(c.fault);
    const std::string name = "robot" + std::to_string(round++);
    auto robot = fleet.robot(name, "fleet_liar", fleet.publicKey());
    client::Client client(robotClientOptions());
    client::Function f = client.function(client.loadModel(arm7Text()), kFleetSpec);
    rpc::FleetFigures last;
    ASSERT_TRUE(waitFleet(client, [](const rpc::FleetFigures& x) { return x.fetch_failures >= 1; },
                          std::chrono::seconds(90), &last))
        << robot->log();
    EXPECT_EQ(last.artifacts_refused, 1u);
    EXPECT_EQ(last.artifacts_fetched, 0u);
    EXPECT_NE(last.peers.at(0).last_problem.find(c.says), std::string::npos) << last.peers[0].last_problem;
    EXPECT_EQ(countEvents(robot->log(), "fleet_artifact_refused"), 1u);
    std::vector<double> out(f.outputCount());
    ASSERT_TRUE(f.evaluate({ref.inputs.data(), static_cast<std::size_t>(ref.inputs.size())}, out).ok());
    EXPECT_TRUE(ref.matches(out));  // the interpreter's
    robot.reset();
    EXPECT_TRUE(cacheEntries(fleet.robotCache(name)).empty());
  }
  // The same build host, honest again: the next robot gets it (the refusals were the faults').
  host.spoil(ArtifactFault::None);
  auto robot = fleet.robot("honest", "fleet_liar", fleet.publicKey());
  client::Client client(robotClientOptions());
  client::Function f = client.function(client.loadModel(arm7Text()), kFleetSpec);
  ASSERT_TRUE(waitCompiled(client, f.id(), std::chrono::seconds(60))) << robot->log();
  EXPECT_EQ(client.fleetStatus().fleet.artifacts_refused, 0u);
}

}  // namespace
}  // namespace robodiff::testing
