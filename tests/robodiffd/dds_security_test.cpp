// robodiffd and DDS Security: open DDS only on loopback (and said so at start), refused
// when DDS reaches other hosts without a keystore; a keystore made by `robodiff security`
// serves the CLI with credentials and nobody without.

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include <string>

#include "dds_exposure.hpp"
#include "robodiffd/robodiffd_process.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using server::cycloneLoopbackOnly;
using server::ddsExposureRefusal;
using server::DdsExposure;

std::string fileUri(const std::string& deploy_file) {
  return "file://" + (sourceDir() / "deploy" / deploy_file).string();
}

TEST(DdsExposure, LoopbackOnlyIsReadFromTheCycloneConfiguration) {
  EXPECT_TRUE(cycloneLoopbackOnly(fileUri("cyclonedds-loopback.xml").c_str()));
  EXPECT_FALSE(cycloneLoopbackOnly(fileUri("cyclonedds-lan.xml").c_str()));  // autodetermine
  EXPECT_TRUE(cycloneLoopbackOnly(nullptr));  // robodiff's embedded loopback configuration
  EXPECT_TRUE(cycloneLoopbackOnly(""));
  EXPECT_TRUE(cycloneLoopbackOnly(
      "<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
      "</General></Domain></CycloneDDS>"));
  EXPECT_FALSE(cycloneLoopbackOnly(
      "<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
      "<NetworkInterface name=\"eth0\"/></Interfaces></General></Domain></CycloneDDS>"));
  EXPECT_FALSE(cycloneLoopbackOnly("<CycloneDDS><!-- <NetworkInterface name=\"lo\"/> --></CycloneDDS>"));
  EXPECT_TRUE(cycloneLoopbackOnly("<NetworkInterfaceAddress>127.0.0.1</NetworkInterfaceAddress>"));
}

TEST(DdsExposure, OpenDdsIsRefusedOnlyWhenItReachesOtherHosts) {
  EXPECT_FALSE(ddsExposureRefusal({.secure = true}));
  EXPECT_FALSE(ddsExposureRefusal({.loopback_only = true}));
  EXPECT_FALSE(ddsExposureRefusal({.allow_unauthenticated = true}));
  const auto refusal = ddsExposureRefusal({});
  ASSERT_TRUE(refusal);
  EXPECT_NE(refusal->find("dds.security"), std::string::npos) << *refusal;
  EXPECT_NE(refusal->find("dds.allow_unauthenticated"), std::string::npos) << *refusal;
}

TEST(RobodiffdDdsSecurity, OpenDdsOnTheLanIsRefusedAtStart) {
  TempDir dir;
  const ProcessResult r = runCommand("CYCLONEDDS_URI=" + shellQuote(fileUri("cyclonedds-lan.xml")) + " " +
                                     shellQuote(robodiffdPath().string()) + " --no-iceoryx --no-http --cache " +
                                     shellQuote((dir / "cache").string()));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("startup_refused"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("dds.allow_unauthenticated"), std::string::npos) << r.err;
}

TEST(RobodiffdDdsSecurity, OpenDdsOnLoopbackSaysSoAtStart) {
  TempDir dir;
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log", {"--no-iceoryx", "--no-http"});
  const auto open = logEvent(server.log(), "dds_open");
  ASSERT_FALSE(open.is_null()) << server.log();
  EXPECT_EQ(open["loopback_only"], true);
  EXPECT_EQ(logEvent(server.log(), "dds_server_started")["security"], "open (unauthenticated)");
}

// With no CYCLONEDDS_URI at all, robodiffd and its clients both use the embedded loopback
// configuration: the server starts (open, saying so) and the CLI finds it.
TEST(RobodiffdDdsSecurity, WithoutCycloneConfigurationBothSidesMeetOnLoopback) {
  TempDir dir;
  const std::string domain = std::to_string(testDomain());
  const std::string log = (dir / "robodiffd.log").string();
  const ProcessResult r = runCommand(  // one subshell, so that runCommand's redirections take its output
      "(env -u CYCLONEDDS_URI " + shellQuote(robodiffdPath().string()) + " --no-iceoryx --no-http --log-format json" +
      " --dds-domain " + domain + " --cache " + shellQuote((dir / "cache").string()) + " 2> " + shellQuote(log) +
      " & pid=$!; for i in $(seq 300); do grep -q '\"event\":\"serving\"' " + shellQuote(log) +
      " && break; sleep 0.1; done; env -u CYCLONEDDS_URI " + shellQuote(cliPath().string()) + " health --server dds:" + domain +
      " --timeout 20; rc=$?; kill -TERM $pid; wait $pid; exit $rc)");
  std::ifstream in(log);
  const std::string server_log((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(r.exit_code, 0) << r.err << server_log;
  EXPECT_NE(r.out.find("SERVING"), std::string::npos) << r.out << r.err;
  const auto open = logEvent(server_log, "dds_open");
  ASSERT_FALSE(open.is_null()) << server_log;
  EXPECT_EQ(open["loopback_only"], true);
}

TEST(RobodiffdDdsSecurity, KeystoreServesTheCliWithCredentialsOnly) {
  TempDir dir;
  const std::string keystore = (dir / "keystore").string();
  ProcessResult r = runCommand(shellQuote(cliPath().string()) + " security init " + shellQuote(keystore) + " && " +
                               shellQuote(cliPath().string()) + " security add-client " + shellQuote(keystore) +
                               " alice");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ROBODIFF_DDS_SECURITY=" + keystore + "/alice"), std::string::npos) << r.out;

  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log",
                          {"--no-iceoryx", "--no-http", "--set", "dds.security=" + keystore});
  EXPECT_TRUE(logEvent(server.log(), "dds_open").is_null()) << server.log();
  const std::string health = shellQuote(cliPath().string()) + " health --server dds:" + std::to_string(testDomain());
  r = runCommand("ROBODIFF_DDS_SECURITY=" + shellQuote(keystore + "/alice") + " " + health + " --timeout 15");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("SERVING"), std::string::npos) << r.out;
  r = runCommand(health + " --timeout 3");  // no credentials
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
}

}  // namespace
}  // namespace robodiff::testing
