// deploy/: the systemd units, the sysusers file, the Cyclone DDS configurations and the
// RouDi configuration, each checked by the tool that will read it:
// - the units with `systemd-analyze verify` (a copy whose ExecStart= points at a stub,
//   since robodiffd is not installed in /usr/local/bin here), which must say nothing;
// - the sysusers file with `systemd-sysusers --dry-run` under a scratch root;
// - each cyclonedds*.xml by creating a DDS domain and a participant from it;
// - deploy/roudi.toml by starting iox-roudi with it until it is ready for clients.
// Each check also runs on a deliberately broken copy, which must fail, so that a pass
// means the tool really read the file. A missing tool skips its tests with a message.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <gtest/gtest.h>

#include "shm/roudi_fixture.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace fs = std::filesystem;
using robodiff::testing::readFile;
using robodiff::testing::runCommand;
using robodiff::testing::shellQuote;
using robodiff::testing::sourceDir;
using robodiff::testing::TempDir;

namespace {

fs::path deployDir() { return sourceDir() / "deploy"; }

bool haveProgram(const std::string& name) {
  return runCommand("command -v " + shellQuote(name) + " >/dev/null 2>&1").exit_code == 0;
}

// `text` with every occurrence of `from` replaced; fails the test when there is none, so
// a broken copy can never silently equal the original.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("'" + from + "' is not in the file");
  for (auto p = at; p != std::string::npos; p = text.find(from, p + to.size())) text.replace(p, from.size(), to);
  return text;
}

// ---------------------------------------------------------------------------- systemd

const std::vector<std::string> kUnits{"iox-roudi.service", "robodiffd.service"};

// Copies of the units in dir, with robodiffd's ExecStart= pointing at an executable stub
// (verify checks that the command exists). Returns the copies' paths.
std::vector<fs::path> unitCopies(const TempDir& dir, const std::string& robodiffd_text) {
  const fs::path stub = dir.script("robodiffd", "exit 0");
  dir.file("robodiffd.service", replaced(robodiffd_text, "/usr/local/bin/robodiffd", stub.string()));
  dir.file("iox-roudi.service", readFile(deployDir() / "systemd" / "iox-roudi.service"));
  return {dir / "iox-roudi.service", dir / "robodiffd.service"};
}

robodiff::testing::ProcessResult verify(const std::vector<fs::path>& units) {
  std::string command = "systemd-analyze verify";
  for (const auto& u : units) command += " " + shellQuote(u.string());
  return runCommand(command);
}

#define REQUIRE_PROGRAM(name)                                                                       \
  if (!haveProgram(name)) GTEST_SKIP() << name << " is not installed here: cannot check the files it reads"

TEST(DeployUnits, SystemdAnalyzeVerifiesBothUnitsWithoutAWord) {
  REQUIRE_PROGRAM("systemd-analyze");
  if (!fs::exists("/usr/bin/iox-roudi")) GTEST_SKIP() << "/usr/bin/iox-roudi (package iceoryx) is not installed";
  TempDir dir;
  const auto result = verify(unitCopies(dir, readFile(deployDir() / "systemd" / "robodiffd.service")));
  EXPECT_EQ(result.exit_code, 0) << result.out << result.err;
  EXPECT_EQ(result.out + result.err, "") << "systemd-analyze verify has something to say";
}

TEST(DeployUnits, SystemdAnalyzeReportsABrokenCopy) {
  REQUIRE_PROGRAM("systemd-analyze");
  if (!fs::exists("/usr/bin/iox-roudi")) GTEST_SKIP() << "/usr/bin/iox-roudi (package iceoryx) is not installed";
  const std::string text = readFile(deployDir() / "systemd" / "robodiffd.service");
  {  // a misspelt key
    TempDir dir;
    const auto result = verify(unitCopies(dir, replaced(text, "KillMode=mixed", "KilMode=mixed")));
    EXPECT_NE((result.out + result.err).find("Unknown key"), std::string::npos) << result.out << result.err;
  }
  {  // a bad value
    TempDir dir;
    const auto result = verify(unitCopies(dir, replaced(text, "Restart=on-failure", "Restart=sometimes")));
    EXPECT_NE((result.out + result.err).find("restart"), std::string::npos) << result.out << result.err;
  }
  {  // a command that is not there
    TempDir dir;
    auto units = unitCopies(dir, text);
    dir.file("robodiffd.service", replaced(readFile(units[1]), dir.path().string() + "/robodiffd",
                                           dir.path().string() + "/no-such-robodiffd"));
    const auto result = verify(units);
    EXPECT_NE(result.exit_code, 0);
    EXPECT_NE((result.out + result.err).find("no-such-robodiffd"), std::string::npos) << result.out << result.err;
  }
}

// What the design relies on, spelt out (systemd accepts each alternative just as well).
TEST(DeployUnits, UnitsCarryTheDesignDecisions) {
  const std::string roudi = readFile(deployDir() / "systemd" / "iox-roudi.service");
  const std::string server = readFile(deployDir() / "systemd" / "robodiffd.service");
  auto has = [](const std::string& text, const std::string& line) {
    return std::regex_search(text, std::regex("(^|\n)" + line + "(\n|$)"));
  };
  for (const std::string* unit : {&roudi, &server}) {
    EXPECT_TRUE(has(*unit, "User=robodiff"));
    EXPECT_TRUE(has(*unit, "Group=robodiff"));
    EXPECT_TRUE(has(*unit, "NoNewPrivileges=yes"));
    EXPECT_TRUE(has(*unit, "PrivateTmp=no")) << "iceoryx's sockets are in the host's /tmp";
    EXPECT_FALSE(has(*unit, "DynamicUser=yes"));
    EXPECT_FALSE(has(*unit, "PrivateDevices=yes")) << "the segments are in the host's /dev/shm";
  }
  EXPECT_TRUE(has(roudi, "ExecStart=/usr/bin/iox-roudi -c /etc/robodiff/roudi.toml.*"));
  EXPECT_TRUE(has(server, "BindsTo=iox-roudi.service"));
  EXPECT_TRUE(has(server, "After=iox-roudi.service"));
  EXPECT_TRUE(has(server, "ExecStart=/usr/local/bin/robodiffd .*--roudi external.*"));
  EXPECT_TRUE(has(server, "ExecStart=.*--cache /var/cache/robodiff.*"));
  EXPECT_TRUE(has(server, "CacheDirectory=robodiff"));
  EXPECT_TRUE(has(server, "CacheDirectoryMode=0700"));
  EXPECT_TRUE(has(server, "RestartPreventExitStatus=2"));
  EXPECT_TRUE(has(server, "Environment=CYCLONEDDS_URI=file:///etc/robodiff/cyclonedds.xml"));
}

TEST(DeployUnits, SysusersFileCreatesTheServiceUser) {
  REQUIRE_PROGRAM("systemd-sysusers");
  TempDir root;
  fs::create_directories(root / "etc");
  const auto good = runCommand("systemd-sysusers --dry-run --root=" + shellQuote(root.path().string()) + " " +
                               shellQuote((deployDir() / "systemd" / "robodiff.sysusers").string()));
  EXPECT_EQ(good.exit_code, 0) << good.out << good.err;
  EXPECT_NE((good.out + good.err).find("Creating user 'robodiff'"), std::string::npos) << good.out << good.err;
  EXPECT_EQ((good.out + good.err).find("gnoring"), std::string::npos) << good.out << good.err;

  const fs::path bad = root.file("bad.sysusers", replaced(readFile(deployDir() / "systemd" / "robodiff.sysusers"),
                                                          "\nu robodiff", "\nx robodiff"));
  const auto broken = runCommand("systemd-sysusers --dry-run --root=" + shellQuote(root.path().string()) + " " +
                                 shellQuote(fs::absolute(bad).string()));
  EXPECT_EQ((broken.out + broken.err).find("Creating user 'robodiff'"), std::string::npos) << broken.out << broken.err;
  EXPECT_NE(broken.exit_code, 0) << broken.out << broken.err;
}

// ------------------------------------------------------------------------- Cyclone DDS

// A domain from `config` (file:// URI, as in CYCLONEDDS_URI) and a participant in it; the
// return code of the first call that failed, else DDS_RETCODE_OK.
dds_return_t startParticipant(dds_domainid_t domain_id, const fs::path& config) {
  const std::string uri = "file://" + fs::absolute(config).string();
  const dds_entity_t domain = dds_create_domain(domain_id, uri.c_str());
  if (domain < 0) return domain;
  const dds_entity_t participant = dds_create_participant(domain_id, nullptr, nullptr);
  dds_delete(domain);  // the participant with it
  return participant < 0 ? participant : DDS_RETCODE_OK;
}

// Domain ids of their own, away from those the other tests use on loopback.
constexpr dds_domainid_t kLoopbackDomain = 201, kLanDomain = 202, kBrokenDomain = 203;

TEST(DeployCyclone, LoopbackConfigurationStartsAParticipant) {
  const dds_return_t rc = startParticipant(kLoopbackDomain, deployDir() / "cyclonedds-loopback.xml");
  EXPECT_EQ(rc, DDS_RETCODE_OK) << dds_strretcode(rc);
}

TEST(DeployCyclone, LanConfigurationStartsAParticipant) {
  // Its peers are placeholders that do not answer: Cyclone keeps probing them, and the
  // participant starts all the same.
  const dds_return_t rc = startParticipant(kLanDomain, deployDir() / "cyclonedds-lan.xml");
  EXPECT_EQ(rc, DDS_RETCODE_OK) << dds_strretcode(rc);
}

TEST(DeployCyclone, BrokenCopiesAreRefused) {
  struct Case {
    const char* file;
    const char* from;
    const char* to;
  };
  const Case cases[] = {
      {"cyclonedds-lan.xml", "<AllowMulticast>false</AllowMulticast>", "<AllowMulticast>sometimes</AllowMulticast>"},
      {"cyclonedds-lan.xml", "<Peers>", "<Peerz><Peers>"},  // not well-formed
      {"cyclonedds-lan.xml", "<ParticipantIndex>", "<ParticipantIndexx>auto</ParticipantIndexx><ParticipantIndex>"},
      {"cyclonedds-loopback.xml", "name=\"lo\"", "name=\"no-such-if0\""},  // an interface that is not there
  };
  for (const Case& c : cases) {
    TempDir dir;
    const fs::path copy = dir.file(c.file, replaced(readFile(deployDir() / c.file), c.from, c.to));
    EXPECT_LT(startParticipant(kBrokenDomain, copy), 0) << c.file << " with '" << c.to << "' was accepted";
  }
}

// ------------------------------------------------------------------------------ RouDi

TEST(DeployRoudi, StartsWithTheDeployConfiguration) {
  if (!haveProgram("iox-roudi")) GTEST_SKIP() << "iox-roudi (package iceoryx) is not installed";
  if (robodiff::shm::roudiRunning()) GTEST_SKIP() << "a RouDi is already running on this host; cannot start one";
  robodiff::testing::RoudiProcess roudi(deployDir() / "roudi.toml");  // throws unless ready for clients
  EXPECT_TRUE(roudi.started());
  EXPECT_TRUE(robodiff::shm::roudiRunning());
  roudi.stop();  // SIGKILL, then its socket and segments removed
  EXPECT_FALSE(robodiff::shm::roudiRunning());
}

TEST(DeployRoudi, RefusesABrokenCopy) {
  if (!haveProgram("iox-roudi")) GTEST_SKIP() << "iox-roudi (package iceoryx) is not installed";
  if (robodiff::shm::roudiRunning()) GTEST_SKIP() << "a RouDi is already running on this host; cannot start one";
  const std::string text = readFile(deployDir() / "roudi.toml");
  const std::string broken[] = {
      replaced(text, "size = 1024\n", "count_only = 1024\n"),  // a mempool without its chunk size
      replaced(text, "[[segment.mempool]]", "[[segment.mempol]]"),  // a segment without mempools
      replaced(text, "version = 1", "version = [1"),                // not TOML
  };
  for (const std::string& content : broken) {
    TempDir dir;
    const fs::path copy = dir.file("roudi.toml", content);
    try {
      robodiff::testing::RoudiProcess roudi(copy, std::chrono::seconds(10));
      ADD_FAILURE() << "iox-roudi started with a broken configuration:\n" << content;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("exited before it was ready"), std::string::npos) << e.what();
    }
    robodiff::shm::removeRoudiLeftovers();
    // RoudiProcess keeps its log when its constructor throws; this one was expected.
    if (std::getenv("ROBODIFF_KEEP_ROUDI_LOG") == nullptr)
      fs::remove(fs::temp_directory_path() / ("robodiff-test-roudi-" + std::to_string(::getpid()) + ".log"));
  }
}

}  // namespace
