// A real robodiffd sent a URDF nested 100,000 deep (which once overflowed its stack in
// the URDF parser): it answers RESOURCE_EXHAUSTED naming the limit, stays up, and loads
// a good robot right after; over both transports.
#include <signal.h>

#include "robodiffd/service_fixture.hpp"

namespace robodiff::testing {
namespace {

class UrdfAttack : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() { signal(SIGTERM, SIG_IGN); }  // see EndToEnd: RouDi's stop
  TempDir dir_;
  RoudiProcess& roudi_ = sharedRoudi();
};

std::string deeplyNested(int depth) {
  std::string xml = "<robot name=\"r\"><link name=\"base\"/>";
  for (int i = 0; i < depth; ++i) xml += "<a>";
  for (int i = 0; i < depth; ++i) xml += "</a>";
  return xml + "</robot>";
}

TEST_P(UrdfAttack, DeepNestingIsRefusedAndTheServerKeepsServing) {
  RobodiffdProcess server(dir_ / "cache", dir_ / "robodiffd.log", {"--roudi", "external"});
  ASSERT_TRUE(server.running());
  auto c = connectTo(GetParam());
  // DDS samples are at most 512 KiB by default: 60,000 levels (420 KB) over DDS.
  const int depth = GetParam() == "dds" ? 60'000 : 100'000;
  rpc::LoadModelRequest attack;
  attack.urdf = deeplyNested(depth);
  rpc::LoadModelReply reply;
  const Status refused = c->loadModel(attack, reply);
  EXPECT_EQ(refused.code, StatusCode::ResourceExhausted) << toString(refused.code) << ": " << refused.message;
  EXPECT_NE(refused.message.find("deep; the limit is max_depth = 64"), std::string::npos) << refused.message;
  EXPECT_TRUE(server.running()) << server.log();

  rpc::LoadModelRequest good;
  good.urdf = arm7Text();
  const Status loaded = c->loadModel(good, reply);
  EXPECT_TRUE(loaded.ok()) << toString(loaded.code) << ": " << loaded.message;
  EXPECT_EQ(reply.nq, 7u);
}

INSTANTIATE_TEST_SUITE_P(Transports, UrdfAttack, ::testing::Values("iceoryx", "dds"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
}  // namespace robodiff::testing
