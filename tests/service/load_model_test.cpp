// LoadModel on a real Service: names and sizes of arm7, the canonical hash as the id (the
// same robot twice is one model with two references; an edited mass is another model,
// and both keep working), and the checks on what is sent (URDF errors naming the line,
// options_json keys, size and count limits).
#include <algorithm>
#include <regex>

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

TEST(LoadModel, Arm7HasItsJointsFramesAndSizes) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply m = loadModel(*service, arm7Urdf());
  EXPECT_EQ(m.model_id.size(), 64u);
  EXPECT_TRUE(std::regex_match(m.model_id, std::regex("[0-9a-f]{64}"))) << m.model_id;
  EXPECT_EQ(m.nq, 7u);
  EXPECT_EQ(m.nv, 7u);
  const std::vector<std::string> joints = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6", "joint7"};
  EXPECT_EQ(m.joint_names, joints);
  auto has = [&](const std::string& frame) {
    return std::find(m.frame_names.begin(), m.frame_names.end(), frame) != m.frame_names.end();
  };
  EXPECT_TRUE(has("universe"));
  EXPECT_TRUE(has("base_link"));
  EXPECT_TRUE(has("link1"));
  EXPECT_TRUE(has("joint7"));
  EXPECT_NE(ws.logText().find("\"event\":\"model_loaded\""), std::string::npos) << ws.logText();
}

TEST(LoadModel, SameRobotIsOneModelAndAnEditedMassAnother) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string urdf = arm7Urdf();
  const rpc::LoadModelReply a = loadModel(*service, urdf);
  // Whitespace and comments do not change the robot.
  const rpc::LoadModelReply again = loadModel(*service, "<!-- the same arm -->\n" + urdf + "\n\n");
  EXPECT_EQ(again.model_id, a.model_id);
  const std::string heavier = replaced(urdf, R"(<mass value="2.3056640625"/>)", R"(<mass value="2.5"/>)");
  const rpc::LoadModelReply b = loadModel(*service, heavier);
  EXPECT_NE(b.model_id, a.model_id);
  EXPECT_EQ(health(*service).models_loaded, 2u);

  // Both serve RNEA, and the heavier link changes the torques.
  const rpc::GetFunctionReply fa = readyFunction(*service, a.model_id, kRneaValueSpec);
  const rpc::GetFunctionReply fb = readyFunction(*service, b.model_id, kRneaValueSpec);
  EXPECT_NE(fa.function_id, fb.function_id);
  const std::vector<double> x = someInputs(21, 1);
  const std::vector<double> ta = evaluateOnce(*service, fa, x), tb = evaluateOnce(*service, fb, x);
  ASSERT_EQ(ta.size(), 7u);
  EXPECT_NE(ta, tb);

  // The first id took two references: two releases to let it go.
  rpc::ReleaseReply released;
  ASSERT_TRUE(service->release(context(), {a.model_id}, released).ok());
  EXPECT_EQ(released.references_left, 1u);
}

TEST(LoadModel, FloatingBaseIsAnotherModel) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const rpc::LoadModelReply fixed = loadModel(*service, arm7Urdf());
  const rpc::LoadModelReply floating = loadModel(*service, arm7Urdf(), true);
  EXPECT_NE(floating.model_id, fixed.model_id);
  EXPECT_EQ(floating.nq, 14u);
  EXPECT_EQ(floating.nv, 13u);
}

TEST(LoadModel, BadUrdfIsInvalidArgumentNamingTheLine) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  std::string urdf = arm7Urdf();
  const std::string bad = replaced(urdf, R"(<mass value="2.3056640625"/>)", R"(<mass value="heavy"/>)");
  const auto at = bad.find("heavy");
  const int line = 1 + static_cast<int>(std::count(bad.begin(), bad.begin() + static_cast<long>(at), '\n'));
  rpc::LoadModelRequest request;
  request.urdf = bad;
  request.options_json = R"({"source_name": "bad.urdf"})";
  rpc::LoadModelReply reply;
  const Status status = service->loadModel(context(), request, reply);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("bad.urdf:" + std::to_string(line) + ":"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("heavy"), std::string::npos) << status.message;
  EXPECT_TRUE(reply.model_id.empty());
  EXPECT_EQ(health(*service).models_loaded, 0u);

  request.urdf = "<robot name='x'>";
  request.options_json.clear();
  EXPECT_EQ(service->loadModel(context(), request, reply).code, StatusCode::InvalidArgument);
}

TEST(LoadModel, OptionsJsonMustBeAnObjectOfKnownKeys) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  rpc::LoadModelRequest request;
  request.urdf = arm7Urdf();
  rpc::LoadModelReply reply;
  request.options_json = R"({"gravity": [0, 0, -9.81]})";
  Status status = service->loadModel(context(), request, reply);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("\"gravity\""), std::string::npos) << status.message;
  request.options_json = "[1, 2]";
  EXPECT_EQ(service->loadModel(context(), request, reply).code, StatusCode::InvalidArgument);
  request.options_json = "{not json";
  EXPECT_EQ(service->loadModel(context(), request, reply).code, StatusCode::InvalidArgument);
  request.options_json = R"({"source_name": "arm7.urdf"})";
  EXPECT_TRUE(service->loadModel(context(), request, reply).ok());
  request.options_json = "  ";
  EXPECT_TRUE(service->loadModel(context(), request, reply).ok());
}

TEST(LoadModel, LimitsOnSizeAndCount) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.max_urdf_bytes = 1000;
  options.max_models = 1;
  auto service = ws.start(options);
  rpc::LoadModelRequest request;
  request.urdf = arm7Urdf();
  rpc::LoadModelReply reply;
  Status status = service->loadModel(context(), request, reply);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_NE(status.message.find("max_urdf_bytes"), std::string::npos) << status.message;

  options.max_urdf_bytes = std::size_t{1} << 20;
  service.reset();
  service = ws.start(options);
  const rpc::LoadModelReply first = loadModel(*service, arm7Urdf());
  EXPECT_EQ(loadModel(*service, arm7Urdf()).model_id, first.model_id);  // not a new model
  request.urdf = replaced(arm7Urdf(), R"(<mass value="2.3056640625"/>)", R"(<mass value="2.5"/>)");
  status = service->loadModel(context(), request, reply);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_NE(status.message.find("max_models"), std::string::npos) << status.message;
}

}  // namespace
}  // namespace robodiff::server::testing
