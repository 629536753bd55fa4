// Failed and oversized requests never hold the service's slots or memory, and what the
// service says about them stays short: failed functions are unloaded at once (the
// dashboard keeps a bounded record), specs and the names in them have limits, errors and
// log lines quote client input as a short prefix.
#include <unistd.h>

#include <fstream>

#include "robodiff/functions/function_spec.hpp"
#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

std::string fkSpec(const std::string& frame) {
  return R"({"function": "fk", "frame": ")" + frame + R"(", "outputs": [{"kind": "value"}]})";
}

// The process's resident memory (the second field of /proc/self/statm, in pages).
std::uint64_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
}

TEST(BoundedRequests, FailedSpecsHoldNoSlotAndAGoodSpecStillBuilds) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  ASSERT_EQ(service->options().max_functions, 1024u);
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  for (int i = 0; i < 1030; ++i) {
    rpc::GetFunctionReply reply;
    const Status status = getFunction(*service, model_id, fkSpec("missing_frame_" + std::to_string(i)), true, reply);
    ASSERT_EQ(status.code, StatusCode::InvalidArgument) << i << ": " << status.message;
    ASSERT_EQ(reply.state, rpc::FunctionState::Failed);
  }
  EXPECT_EQ(health(*service).functions_loaded, 0u);
  // Not RESOURCE_EXHAUSTED: the failures took no slot.
  const rpc::GetFunctionReply good = readyFunction(*service, model_id, kRneaValueSpec);
  const std::vector<double> tau = evaluateOnce(*service, good, std::vector<double>(21, 0.1));
  EXPECT_EQ(tau.size(), 7u);
  EXPECT_EQ(health(*service).functions_loaded, 1u);
  // The dashboard keeps the latest failures only, newest first, each marked invalid-spec.
  const ServiceOverview o = service->overview();
  ASSERT_EQ(o.build_failures.size(), 64u);
  EXPECT_NE(o.build_failures[0].message.find("missing_frame_1029"), std::string::npos) << o.build_failures[0].message;
  for (const ServiceOverview::BuildFailure& f : o.build_failures) EXPECT_EQ(f.stage, "invalid-spec");
  // The model is still loaded (its reference is the client's) and releasable.
  rpc::ReleaseReply released;
  EXPECT_TRUE(service->release(context(), {model_id}, released).ok());
}

TEST(BoundedRequests, ASpecPastMaxSpecBytesIsRefusedNamingTheLimit) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.max_spec_bytes = 4096;
  auto service = ws.start(options);
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  const std::string spec =
      R"({"function": "rnea", "outputs": [{"kind": "value"}], "description": ")" + std::string(5000, 'x') + "\"}";
  rpc::GetFunctionReply reply;
  const Status status = getFunction(*service, model_id, spec, true, reply);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_NE(status.message.find("max_spec_bytes"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("4096"), std::string::npos) << status.message;
  EXPECT_EQ(ServiceOptions{}.max_spec_bytes, std::size_t{1} << 20);
  readyFunction(*service, model_id, kRneaValueSpec);  // still serving
}

TEST(BoundedRequests, NamesPastTheLimitAreRefusedAndLongNamesAreQuotedShort) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  rpc::GetFunctionReply reply;
  // Past kMaxSpecNameBytes: refused before use, naming the limit.
  Status status = getFunction(*service, model_id, fkSpec(std::string(kMaxSpecNameBytes + 1, 'f')), true, reply);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_NE(status.message.find("frame"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find(std::to_string(kMaxSpecNameBytes)), std::string::npos) << status.message;
  EXPECT_LT(status.message.size(), 400u) << status.message;
  // An unknown key just as long.
  status = getFunction(*service, model_id,
                       R"({"function": "rnea", "outputs": [{"kind": "value"}], ")" + std::string(100000, 'k') + "\": 1}",
                       true, reply);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_LT(status.message.size(), 400u) << status.message;
  // Within the limit but unknown: the error quotes a prefix and the size.
  status = getFunction(*service, model_id, fkSpec(std::string(200, 'g')), true, reply);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("(200 bytes)"), std::string::npos) << status.message;
  EXPECT_EQ(status.message.find(std::string(121, 'g')), std::string::npos) << status.message;
}

TEST(BoundedRequests, TenMegabyteFrameNamesCostLittleMemoryAndShortErrors) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.max_spec_bytes = std::size_t{64} << 20;  // past the spec limit: the name limit answers
  auto service = ws.start(options);
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  std::vector<std::string> specs;
  for (char c : {'a', 'b', 'c', 'd'}) specs.push_back(fkSpec(std::string(10 << 20, c)));
  const std::uint64_t before = residentBytes();
  for (const std::string& spec : specs) {
    rpc::GetFunctionReply reply;
    const Status status = getFunction(*service, model_id, spec, true, reply);
    EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
    EXPECT_LT(status.message.size(), 1024u) << status.message.substr(0, 2000);
  }
  const std::uint64_t after = residentBytes();
  specs.clear();
  const std::uint64_t growth = after > before ? after - before : 0;
  std::printf("[ measured ] resident memory growth after four 10 MB frame names: %.1f MB\n", growth / 1e6);
  EXPECT_LT(growth, std::uint64_t{60} << 20);
  // Also with the default limit: refused by size, before any parsing.
  ServiceWorkspace other;
  auto defaults = other.start(other.options());
  const std::string other_model = loadModel(*defaults, arm7Urdf()).model_id;
  rpc::GetFunctionReply reply;
  const Status status = getFunction(*defaults, other_model, fkSpec(std::string(10 << 20, 'e')), true, reply);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_NE(status.message.find("max_spec_bytes"), std::string::npos) << status.message.substr(0, 2000);
  // Nothing of the names reached the log, and the service still serves.
  EXPECT_LT(ws.logText().size(), std::size_t{64} << 10);
  readyFunction(*service, model_id, kRneaValueSpec);
}

TEST(BoundedRequests, LoadModelQuotesItsOptionsShort) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  rpc::LoadModelRequest request;
  request.urdf = arm7Urdf();
  rpc::LoadModelReply reply;
  request.options_json = R"({"source_name": ")" + std::string(1 << 20, 's') + "\"}";
  Status status = service->loadModel(context(), request, reply);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("256"), std::string::npos) << status.message.substr(0, 300);
  EXPECT_LT(status.message.size(), 300u);
  request.options_json = R"({")" + std::string(1 << 20, 'k') + "\": 1}";
  status = service->loadModel(context(), request, reply);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_LT(status.message.size(), 300u);
  request.options_json = R"({"source_name": "arm7.urdf"})";
  EXPECT_TRUE(service->loadModel(context(), request, reply).ok());
}

TEST(BoundedRequests, LogLinesAreBounded) {
  TempDir tmp;
  const auto path = tmp / "log.jsonl";
  std::FILE* file = std::fopen(path.c_str(), "w");
  ASSERT_NE(file, nullptr);
  {
    Logger log(file);
    const std::string huge(10 << 20, 'x');
    log.warn("one_long_value", {{"frame", huge}});
    log.warn("many_long_values", {{"a", std::string(2000, 'a')},
                                  {"b", std::string(2000, 'b')},
                                  {"c", std::string(2000, 'c')},
                                  {"d", std::string(2000, 'd')},
                                  {"e", std::string(2000, 'e')}});
    log.info("short", {{"n", 1}});
  }
  std::fclose(file);
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u);
  for (const std::string& line : lines) EXPECT_LE(line.size(), kMaxLogLineBytes) << line.substr(0, 200);
  EXPECT_NE(lines[0].find("(10485760 bytes)"), std::string::npos);
  EXPECT_NE(lines[1].find("\"event\":\"many_long_values\""), std::string::npos) << lines[1].substr(0, 200);
  EXPECT_NE(lines[1].find("\"line_bytes\":"), std::string::npos) << lines[1].substr(0, 200);
  EXPECT_NE(lines[2].find("\"event\":\"short\""), std::string::npos);
}

}  // namespace
}  // namespace robodiff::server::testing
