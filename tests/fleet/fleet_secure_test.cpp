// A fleet over DDS Security (issue 23): one keystore (made by the project's own
// initKeystore / addIdentity), the build host's server identity, and per robot one server
// identity that also calls the build host's service (KeystoreOptions::also_calls): its
// server and its fleet client are two participants in one process. A robot whose identity
// may not call the build host is refused at start, naming the topic.
#include <cstdlib>

#include <gtest/gtest.h>

#include "fleet/fleet_hosts.hpp"
#include "robodiff/client/dds_keystore.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/process.hpp"

namespace robodiff::testing {
namespace {

// ROBODIFF_DDS_SECURITY for this process's clients while it lives.
class ClientIdentity {
 public:
  explicit ClientIdentity(const std::string& value) { ::setenv("ROBODIFF_DDS_SECURITY", value.c_str(), 1); }
  ~ClientIdentity() { ::unsetenv("ROBODIFF_DDS_SECURITY"); }
};

client::KeystoreOptions forService(const std::string& service) {
  client::KeystoreOptions o;
  o.service_name = service;
  return o;
}

TEST(FleetSecure, ARobotFetchesWithItsOwnIdentityAndOneNotPermittedIsRefusedAtStart) {
  FleetHosts fleet;
  const std::string ks = (fleet.path() / "keystore").string();
  client::initKeystore(ks, "fleetbuild", forService("fleetbuild"));
  client::KeystoreOptions robot_keys = forService("robodiff");
  robot_keys.also_calls = {"fleetbuild"};
  client::addIdentity(ks, "robot1", client::IdentityRole::Server, robot_keys);
  client::addIdentity(ks, "alice", client::IdentityRole::Client, forService("robodiff"));
  const ClientIdentity alice(ks + "/alice");
  auto build = fleet.buildHost("fleetbuild", {"dds.security=" + ks, "dds.security_identity=fleetbuild"});
  const RneaReference ref = RneaReference::at(loadUrdfString(arm7Text()), 11);
  {
    auto robot = fleet.robot("robot1", "fleetbuild", fleet.publicKey(),
                             {"dds.security=" + ks, "dds.security_identity=robot1"});
    client::Client c(robotClientOptions());
    client::Function f = c.function(c.loadModel(arm7Text()), kFleetSpec);
    ASSERT_TRUE(waitCompiled(c, f.id(), std::chrono::seconds(60))) << robot->log() << build->log();
    std::vector<double> out(f.outputCount());
    ASSERT_TRUE(f.evaluate({ref.inputs.data(), static_cast<std::size_t>(ref.inputs.size())}, out).ok());
    EXPECT_TRUE(ref.matches(out));
    EXPECT_EQ(c.fleetStatus().fleet.artifacts_fetched, 1u);
    EXPECT_NE(build->log().find("\"caller\":\"dds:robot1\""), std::string::npos) << build->log();  // authenticated
  }
  // An identity that may call another build service, not this one: Cyclone's access
  // control refuses its fleet participant the build host's topics, and robodiffd says so
  // at start instead of running a robot that can never fetch.
  robot_keys.also_calls = {"otherbuild"};
  client::addIdentity(ks, "intruder", client::IdentityRole::Server, robot_keys);
  const std::string robodiffd = shellQuote(robodiffdPath().string()) + " --no-iceoryx --no-http --interpreter-only" +
                                " --dds-domain " + std::to_string(testDomain()) + " --cache " +
                                shellQuote((fleet.path() / "intruder-cache").string()) + " --set dds.security=" + ks +
                                " --set dds.security_identity=intruder --set fleet.role=robot" +
                                " --set fleet.build_hosts=fleetbuild --set fleet.trusted_keys=" +
                                fleet.publicKey().string();
  const ProcessResult r = runCommand("timeout 20 " + robodiffd);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("Not Allowed By Security"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fleetbuild_request"), std::string::npos) << r.err;
  EXPECT_EQ(countEvents(build->log(), "fleet_artifact_served"), 1u);  // robot1's only
}

}  // namespace
}  // namespace robodiff::testing
