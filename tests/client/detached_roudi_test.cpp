// iceoryx.roudi = detached: robodiffd starts a RouDi that stays when robodiffd exits, so
// a shm client (registered with that RouDi, which iceoryx 2.0 cannot leave) survives a
// robodiffd restart: UNAVAILABLE while none serves, correct values again once the next
// robodiffd (which finds the same RouDi) has its function registered again.
#include <signal.h>

#include <regex>

#include "client/client_fixture.hpp"
#include "robodiff/schema/shm_runtime.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;
using std::chrono::seconds;

// The PID robodiffd logged for the RouDi it started detached; -1 if none.
pid_t detachedRoudiPid(const std::string& log) {
  std::smatch m;
  static const std::regex line(R"("event":"roudi_started_detached"[^\n]*?"pid":([0-9]+))");
  return std::regex_search(log, m, line) ? static_cast<pid_t>(std::stol(m[1])) : -1;
}

// Kills the detached RouDi at the end (not our child: the kernel's reaper collects it).
struct KillRoudiAtEnd {
  pid_t pid = -1;
  ~KillRoudiAtEnd() {
    if (pid <= 0) return;
    ::kill(pid, SIGKILL);
    waitFor([] { return !shm::roudiRunning(); }, seconds(5));
    shm::removeRoudiLeftovers();
  }
};

TEST(DetachedRoudi, ShmClientSurvivesARobodiffdRestart) {
  if (shm::roudiRunning()) GTEST_SKIP() << "a RouDi already runs on this host; this test needs to start its own";
  signal(SIGTERM, SIG_IGN);
  TempDir dir;
  const std::string service = clientTestService(900);
  const std::vector<std::string> args = {"--roudi", "detached", "--set", "iceoryx.service=" + service};
  const Model model = loadUrdfString(arm7Text(), RootJoint::Fixed, "arm7.urdf");
  const RneaReference ref = RneaReference::at(model, 21);
  KillRoudiAtEnd roudi;

  auto first = std::make_unique<RobodiffdProcess>(dir / "cache", dir / "robodiffd-1.log", args);
  ASSERT_TRUE(first->running());
  roudi.pid = detachedRoudiPid(first->log());
  ASSERT_GT(roudi.pid, 0) << "robodiffd did not log the RouDi it started; log:\n" << first->log();

  {
    Client shm(clientOptions(Mode::Shm, dir / "cache", seconds(2), service));
    const client::Function f = shm.function(shm.loadModel(arm7Text()), kRneaJacobianSpec);
    ASSERT_EQ(f.mode(), Mode::Shm);
    std::vector<double> out = outputsFor(f);
    ASSERT_TRUE(f.evaluate(spanOf(ref.inputs), out).ok());
    EXPECT_TRUE(ref.matches(out));

    EXPECT_EQ(first->terminate(), 0) << first->log();
    EXPECT_EQ(::kill(roudi.pid, 0), 0) << "the detached RouDi went with robodiffd";
    EXPECT_TRUE(shm::roudiRunning());
    const Status down = f.evaluate(spanOf(ref.inputs), out);
    EXPECT_EQ(down.code, StatusCode::Unavailable) << toString(down.code) << ": " << down.message;

    RobodiffdProcess second(dir / "cache", dir / "robodiffd-2.log", args);
    ASSERT_TRUE(second.running());
    EXPECT_NE(second.log().find("\"event\":\"roudi_found\""), std::string::npos) << second.log();
    EXPECT_EQ(detachedRoudiPid(second.log()), -1) << "a second RouDi was started";

    Status last;
    const bool back = waitFor([&] {
      std::fill(out.begin(), out.end(), std::nan(""));
      last = f.evaluate(spanOf(ref.inputs), out);
      return last.ok();
    }, seconds(30));
    EXPECT_TRUE(back) << "no good call after the restart; latest: " << toString(last.code) << ": " << last.message
                      << "\nlog:\n" << second.log();
    EXPECT_TRUE(ref.matches(out));
    EXPECT_EQ(second.terminate(), 0) << second.log();
  }
}

}  // namespace
}  // namespace robodiff::testing
