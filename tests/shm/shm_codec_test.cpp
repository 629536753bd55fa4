// The iceoryx chunk layout and codec, without iceoryx: every message round trips, every
// malformed chunk is INVALID_ARGUMENT, deploy/roudi.toml matches the compiled-in pools.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <vector>

#include "robodiff/schema/shm_codec.hpp"
#include "robodiff/schema/shm_mempools.hpp"
#include "support/test_paths.hpp"

namespace robodiff::shm {
namespace {

// A chunk in 8-byte aligned storage, as iceoryx gives.
struct Chunk {
  explicit Chunk(std::size_t size) : words((size + 7) / 8 + 1), size(size) {}
  void* data() { return words.data(); }
  std::vector<std::uint64_t> words;
  std::size_t size;
};

template <class M>
M roundTrip(const M& message) {
  const auto bytes = encode(message);
  M out;
  const Status s = decode(bytes, out);
  EXPECT_TRUE(s.ok()) << s.message;
  // Every prefix is cut off: INVALID_ARGUMENT, never a crash.
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    M partial;
    EXPECT_EQ(decode(std::span(bytes.data(), cut), partial).code, StatusCode::InvalidArgument) << "cut at " << cut;
  }
  auto longer = bytes;
  longer.push_back(std::byte{0});
  M extra;
  EXPECT_EQ(decode(longer, extra).code, StatusCode::InvalidArgument);
  return out;
}

TEST(ShmCodec, LoadModel) {
  rpc::LoadModelRequest req{"<robot name='r'/>", true, R"({"gravity":[0,0,-9.81]})"};
  auto r = roundTrip(req);
  EXPECT_EQ(r.urdf, req.urdf);
  EXPECT_TRUE(r.floating_base);
  EXPECT_EQ(r.options_json, req.options_json);

  rpc::LoadModelReply rep{"abc123", {"j1", "j2"}, {"f1", "", "f3"}, 7, 6};
  auto p = roundTrip(rep);
  EXPECT_EQ(p.model_id, rep.model_id);
  EXPECT_EQ(p.joint_names, rep.joint_names);
  EXPECT_EQ(p.frame_names, rep.frame_names);
  EXPECT_EQ(p.nq, 7u);
  EXPECT_EQ(p.nv, 6u);
}

TEST(ShmCodec, GetFunction) {
  rpc::GetFunctionRequest req{"model", "{\"function\":\"rnea\"}", true};
  auto r = roundTrip(req);
  EXPECT_EQ(r.model_id, "model");
  EXPECT_EQ(r.spec_json, req.spec_json);
  EXPECT_TRUE(r.wait);

  rpc::GetFunctionReply rep;
  rep.function_id = "fn";
  rep.state = rpc::FunctionState::Failed;
  rep.inputs = {{"q", 7}, {"v", 7}};
  rep.outputs = {{"value", rpc::OutputKind::Value, 7, 1, rpc::OutputLayout::DenseRowMajor, 7, {}, {}},
                 {"jac", rpc::OutputKind::Hessian, 2, 3, rpc::OutputLayout::SparseCsr, 3, {0, 2, 3}, {0, 2, 1}}};
  auto p = roundTrip(rep);
  EXPECT_EQ(p.function_id, "fn");
  EXPECT_EQ(p.state, rpc::FunctionState::Failed);
  ASSERT_EQ(p.inputs.size(), 2u);
  EXPECT_EQ(p.inputs[1].name, "v");
  EXPECT_EQ(p.inputs[1].size, 7u);
  ASSERT_EQ(p.outputs.size(), 2u);
  EXPECT_EQ(p.outputs[1].name, "jac");
  EXPECT_EQ(p.outputs[1].kind, rpc::OutputKind::Hessian);
  EXPECT_EQ(p.outputs[1].rows, 2u);
  EXPECT_EQ(p.outputs[1].cols, 3u);
  EXPECT_EQ(p.outputs[1].layout, rpc::OutputLayout::SparseCsr);
  EXPECT_EQ(p.outputs[1].nnz, 3u);
  EXPECT_EQ(p.outputs[1].row_offsets, (std::vector<std::uint32_t>{0, 2, 3}));
  EXPECT_EQ(p.outputs[1].col_indices, (std::vector<std::uint32_t>{0, 2, 1}));
}

TEST(ShmCodec, ListFunctionsReleaseHealthRequests) {
  EXPECT_EQ(roundTrip(rpc::ListFunctionsRequest{"m", 0, ""}).model_id, "m");
  const auto paged = roundTrip(rpc::ListFunctionsRequest{"m", 50, "page-7"});
  EXPECT_EQ(paged.page_size, 50u);
  EXPECT_EQ(paged.page_token, "page-7");
  EXPECT_EQ(roundTrip(rpc::ReleaseRequest{"id-1"}).id, "id-1");
  EXPECT_TRUE(roundTrip(rpc::HealthRequest{true}).verbose);
  EXPECT_EQ(roundTrip(rpc::ReleaseReply{5}).references_left, 5u);

  rpc::ListFunctionsReply rep;
  rep.functions = {{"f1", "m1", "rnea", rpc::FunctionState::Ready, true, 1ull << 40, ""},
                   {"f2", "m1", "aba", rpc::FunctionState::Failed, false, 0, "why"}};
  rep.next_page_token = "17";
  rep.total = 300;
  auto p = roundTrip(rep);
  EXPECT_EQ(p.next_page_token, "17");
  EXPECT_EQ(p.total, 300u);
  ASSERT_EQ(p.functions.size(), 2u);
  EXPECT_EQ(p.functions[0].evaluations, 1ull << 40);
  EXPECT_TRUE(p.functions[0].compiled);
  EXPECT_EQ(p.functions[1].function_name, "aba");
  EXPECT_EQ(p.functions[1].state, rpc::FunctionState::Failed);
  EXPECT_EQ(p.functions[1].message, "why");
  EXPECT_EQ(p.functions[1].model_id, "m1");
}

TEST(ShmCodec, JobMessages) {
  const auto submit = roundTrip(rpc::SubmitJobRequest{"trajopt", R"({"knots": 50})"});
  EXPECT_EQ(submit.kind, "trajopt");
  EXPECT_EQ(submit.params_json, R"({"knots": 50})");
  EXPECT_EQ(roundTrip(rpc::JobStatusRequest{"j1"}).job_id, "j1");
  EXPECT_EQ(roundTrip(rpc::CancelJobRequest{"j2"}).job_id, "j2");
  EXPECT_EQ(roundTrip(rpc::JobResultRequest{"j3"}).job_id, "j3");
  EXPECT_EQ(roundTrip(rpc::SubmitJobReply{"j4"}).job_id, "j4");
  EXPECT_EQ(roundTrip(rpc::CancelJobReply{rpc::JobState::Succeeded}).state, rpc::JobState::Succeeded);

  const rpc::JobInfo info{"j5", "trajectory", rpc::JobState::Running, 0.5, 3.25, 3.5, {"a", "b"}, ""};
  rpc::JobStatusReply status;
  status.jobs = {info, info};
  status.jobs[1].state = rpc::JobState::Cancelled;
  const auto got = roundTrip(status);
  ASSERT_EQ(got.jobs.size(), 2u);
  EXPECT_EQ(got.jobs[0].progress, 0.5);
  EXPECT_EQ(got.jobs[0].elapsed_seconds, 3.25);
  EXPECT_EQ(got.jobs[0].eta_seconds, 3.5);
  EXPECT_EQ(got.jobs[0].messages, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(got.jobs[1].state, rpc::JobState::Cancelled);
  const auto r = roundTrip(rpc::JobResultReply{info, "{}", "/tmp/x"});
  EXPECT_EQ(r.info.job_id, "j5");
  EXPECT_EQ(r.result_dir, "/tmp/x");

  // A state beyond the enum is refused, naming the field.
  auto bytes = encode(rpc::CancelJobReply{rpc::JobState::Queued});
  bytes[0] = std::byte{9};
  rpc::CancelJobReply bad;
  const Status s = decode(bytes, bad);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("state"), std::string::npos) << s.message;
}

// Bytes as they come out of a file: zeros, 0xff, every value between.
std::vector<std::uint8_t> shmCodecTestBytes() {
  std::vector<std::uint8_t> bytes = {0x00, 0xff, 0x00, 0x00, 0x7f, 0x80, 0xff};
  for (int i = 0; i < 256; ++i) bytes.push_back(static_cast<std::uint8_t>(i));
  return bytes;
}

// Appends a value's bytes as the compact encoding lays them out (native order, no padding).
template <class T>
void shmCodecTestAppend(std::vector<std::byte>& out, T value) {
  const auto* p = reinterpret_cast<const std::byte*>(&value);
  out.insert(out.end(), p, p + sizeof value);
}

TEST(ShmCodec, ArtifactMessages) {
  const auto query = roundTrip(rpc::QueryArtifactRequest{"pk-1", "<robot name='a'/>", true,
                                                         R"({"build": {"target": "x86-64-v2"}})", false, true});
  EXPECT_EQ(query.portable_key, "pk-1");
  EXPECT_EQ(query.urdf, "<robot name='a'/>");
  EXPECT_TRUE(query.floating_base);
  EXPECT_EQ(query.spec_json, R"({"build": {"target": "x86-64-v2"}})");
  EXPECT_FALSE(query.build);
  EXPECT_TRUE(query.include_sources);

  const auto building = roundTrip(rpc::QueryArtifactReply{rpc::ArtifactState::Building, "", "", "", 0, 3, ""});
  EXPECT_EQ(building.state, rpc::ArtifactState::Building);
  EXPECT_EQ(building.builds_queued, 3u);
  const auto have = roundTrip(rpc::QueryArtifactReply{rpc::ArtifactState::Have, "key-2", R"({"files": ["lib.so"]})",
                                                      "0a1b", (1ull << 40) + 1, 0, ""});
  EXPECT_EQ(have.state, rpc::ArtifactState::Have);
  EXPECT_EQ(have.key, "key-2");
  EXPECT_EQ(have.manifest_json, R"({"files": ["lib.so"]})");
  EXPECT_EQ(have.signature_hex, "0a1b");
  EXPECT_EQ(have.payload_bytes, (1ull << 40) + 1);

  const auto fetch = roundTrip(rpc::FetchArtifactChunkRequest{"key-2", true, 1ull << 36, 1u << 20});
  EXPECT_EQ(fetch.key, "key-2");
  EXPECT_TRUE(fetch.include_sources);
  EXPECT_EQ(fetch.offset, 1ull << 36);
  EXPECT_EQ(fetch.max_bytes, 1u << 20);

  const std::vector<std::uint8_t> bytes = shmCodecTestBytes();
  const auto chunk = roundTrip(rpc::FetchArtifactChunkReply{5, 1000, bytes});
  EXPECT_EQ(chunk.offset, 5u);
  EXPECT_EQ(chunk.payload_bytes, 1000u);
  EXPECT_EQ(chunk.data, bytes);
  const auto end = roundTrip(rpc::FetchArtifactChunkReply{1000, 1000, {}});
  EXPECT_TRUE(end.data.empty());

  // A state beyond the enum is refused, naming the field.
  auto bad_state = encode(rpc::QueryArtifactReply{});
  bad_state[0] = std::byte{4};
  rpc::QueryArtifactReply refused;
  const Status s = decode(bad_state, refused);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("state has unknown value 4"), std::string::npos) << s.message;
}

// Sequences of numbers go as one block: exactly a count and the values, as element by element.
TEST(ShmCodec, NumberSequencesAreACountThenTheValues) {
  std::vector<std::byte> expected;
  shmCodecTestAppend<std::uint64_t>(expected, 9);
  shmCodecTestAppend<std::uint64_t>(expected, 12);
  shmCodecTestAppend<std::uint32_t>(expected, 3);
  for (std::uint8_t b : {0x00, 0xff, 0x10}) shmCodecTestAppend(expected, b);
  EXPECT_EQ(encode(rpc::FetchArtifactChunkReply{9, 12, {0x00, 0xff, 0x10}}), expected);

  rpc::OutputBlock block{"", rpc::OutputKind::Jacobian, 2, 3, rpc::OutputLayout::SparseCsr, 2, {0, 1, 2}, {0, 2}};
  rpc::GetFunctionReply function{"", rpc::FunctionState::Ready, {}, {block}};
  expected.clear();
  for (std::uint32_t v : {0u, 0u, 0u, 1u,      // function_id "", state, no inputs, one output
                          0u, 1u, 2u, 3u, 1u, 2u,  // name "", kind, rows, cols, layout, nnz
                          3u, 0u, 1u, 2u, 2u, 0u, 2u})  // row_offsets, col_indices
    shmCodecTestAppend(expected, v);
  EXPECT_EQ(encode(function), expected);

  // A byte count beyond the body is refused before anything is allocated, naming the field.
  auto cut = encode(rpc::FetchArtifactChunkReply{0, 3, {1, 2, 3}});
  const std::uint32_t huge = 1u << 30;
  std::memcpy(cut.data() + 16, &huge, sizeof huge);
  rpc::FetchArtifactChunkReply out;
  const Status s = decode(cut, out);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("data claims 1073741824 elements"), std::string::npos) << s.message;
}

TEST(ShmCodec, FleetStatus) {
  EXPECT_TRUE(roundTrip(rpc::FleetStatusRequest{true}).verbose);
  rpc::FleetStatusReply in;
  in.fleet = {"robot", "x86-64-v4", 1, 2, 3, 4, 5, 6, 7, {}};
  in.fleet.peers = {{"build-a", "robodiffd-9", true, 8, 9, 10, 11, 1.5, "hash mismatch in lib.so"},
                    {"build-b", "", false, 0, 0, 0, 0, 0.0, ""}};
  const rpc::FleetFigures f = roundTrip(in).fleet;
  EXPECT_EQ(f.role, "robot");
  EXPECT_EQ(f.target, "x86-64-v4");
  const std::vector<std::uint64_t> counts{f.artifacts_fetched, f.bytes_fetched, f.artifacts_refused,
                                          f.fetch_failures,    f.artifacts_served, f.bytes_served,
                                          f.builds_for_robots};
  for (std::size_t i = 0; i < counts.size(); ++i) EXPECT_EQ(counts[i], i + 1);
  ASSERT_EQ(f.peers.size(), 2u);
  EXPECT_EQ(f.peers[0].service, "build-a");
  EXPECT_EQ(f.peers[0].instance_id, "robodiffd-9");
  EXPECT_TRUE(f.peers[0].reachable);
  EXPECT_EQ(f.peers[0].artifacts_fetched, 8u);
  EXPECT_EQ(f.peers[0].bytes_fetched, 9u);
  EXPECT_EQ(f.peers[0].refusals, 10u);
  EXPECT_EQ(f.peers[0].failures, 11u);
  EXPECT_EQ(f.peers[0].last_problem, "hash mismatch in lib.so");
  EXPECT_EQ(f.peers[1].service, "build-b");
  EXPECT_FALSE(f.peers[1].reachable);
}

TEST(ShmCodec, HealthReplyEveryField) {
  rpc::HealthReply h;
  h.state = rpc::ServingState::Draining;
  h.version = "1.2.3";
  h.server_instance_id = "srv";
  h.uptime_ns = 1;
  h.models_loaded = 2;
  h.functions_loaded = 3;
  h.functions_compiled = 4;
  h.builds_queued = 5;
  h.builds_running = 6;
  h.builds_failed = 7;
  h.builds_done = 8;
  h.cache_hits = 9;
  h.cache_misses = 10;
  h.cache_bytes = 11;
  h.cache_entries = 12;
  h.workers_total = 13;
  h.workers_busy = 14;
  h.queue_depth = 15;
  h.queue_capacity = 16;
  h.batch_threads = 17;
  h.methods = {{rpc::Method::Release, 18, 19, 20, 21, 22, 23}};
  h.errors = {{StatusCode::Unauthenticated, 24}};
  h.transports = {{"iceoryx", 25, 26}, {"dds", 27, 28}};
  auto p = roundTrip(h);
  EXPECT_EQ(p.state, rpc::ServingState::Draining);
  EXPECT_EQ(p.version, "1.2.3");
  EXPECT_EQ(p.server_instance_id, "srv");
  const std::vector<std::uint64_t> got{p.uptime_ns, p.models_loaded, p.functions_loaded, p.functions_compiled,
                                       p.builds_queued, p.builds_running, p.builds_failed, p.builds_done,
                                       p.cache_hits, p.cache_misses, p.cache_bytes, p.cache_entries,
                                       p.workers_total, p.workers_busy, p.queue_depth, p.queue_capacity,
                                       p.batch_threads};
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], i + 1);
  ASSERT_EQ(p.methods.size(), 1u);
  EXPECT_EQ(p.methods[0].method, rpc::Method::Release);
  EXPECT_EQ(p.methods[0].requests, 18u);
  EXPECT_EQ(p.methods[0].max_ns, 23u);
  ASSERT_EQ(p.errors.size(), 1u);
  EXPECT_EQ(p.errors[0].code, StatusCode::Unauthenticated);
  EXPECT_EQ(p.errors[0].count, 24u);
  ASSERT_EQ(p.transports.size(), 2u);
  EXPECT_EQ(p.transports[1].transport, "dds");
  EXPECT_EQ(p.transports[1].errors, 28u);
}

TEST(ShmCodec, EvaluateMessages) {
  rpc::EvaluateRequest e{"fn-id", {1.5, -2, 3}};
  auto r = roundTrip(e);
  EXPECT_EQ(r.function_id, "fn-id");
  EXPECT_EQ(r.inputs, e.inputs);

  rpc::EvaluateBatchRequest b{"f", 2, {1, 2, 3, 4, 5, 6}};
  auto rb = roundTrip(b);
  EXPECT_EQ(rb.knot_count, 2u);
  EXPECT_EQ(rb.inputs, b.inputs);

  EXPECT_EQ(roundTrip(rpc::EvaluateReply{{4, 5}}).outputs, (std::vector<double>{4, 5}));
  rpc::EvaluateBatchReply br{1, 3, 10, 4, 2, {1, 2, 3, 4}};
  auto p = roundTrip(br);
  EXPECT_EQ(p.chunk_index, 1u);
  EXPECT_EQ(p.chunk_count, 3u);
  EXPECT_EQ(p.total_knots, 10u);
  EXPECT_EQ(p.first_knot, 4u);
  EXPECT_EQ(p.knot_count, 2u);
  EXPECT_EQ(p.outputs, br.outputs);
}

TEST(ShmCodec, BadEnumsAndCountsAreInvalid) {
  auto bytes = encode(rpc::HealthReply{});
  std::uint32_t state = 7;
  std::memcpy(bytes.data(), &state, 4);
  rpc::HealthReply h;
  const Status s = decode(bytes, h);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_NE(s.message.find("state"), std::string::npos) << s.message;

  // A string claiming 4 GB.
  auto release = encode(rpc::ReleaseRequest{"abc"});
  std::uint32_t huge = 0xFFFFFFFF;
  std::memcpy(release.data(), &huge, 4);
  rpc::ReleaseRequest r;
  EXPECT_EQ(decode(release, r).code, StatusCode::InvalidArgument);

  // A boolean that is 2.
  auto health = encode(rpc::HealthRequest{true});
  health[0] = std::byte{2};
  rpc::HealthRequest hr;
  EXPECT_EQ(decode(health, hr).code, StatusCode::InvalidArgument);
}

TEST(ShmCodec, RequestChunkRoundTripAndMalformedHeaders) {
  rpc::RequestHeader header;
  header.client_id = "host:42:deadbeef";
  header.correlation_id = 99;
  header.deadline_budget_ns = 5'000'000;
  header.server_instance_id = "srv-1";
  header.schema_version = {1, 3};
  const double inputs[] = {1, 2, 3};
  const std::size_t body = evaluateRequestBodySize(3, 3);
  Chunk chunk(chunkSize(0, body));
  writeRequestHeader(chunk.data(), header, rpc::Method::Evaluate, body);
  auto in = writeEvaluateRequestBody(bodyOf(chunk.data()), "abc", 1, 3);
  std::copy(std::begin(inputs), std::end(inputs), in.begin());

  RequestView view;
  ASSERT_TRUE(parseRequest(chunk.data(), chunk.size, view).ok());
  EXPECT_EQ(view.method, rpc::Method::Evaluate);
  EXPECT_EQ(view.header.client_id, header.client_id);
  EXPECT_EQ(view.header.correlation_id, 99u);
  EXPECT_EQ(view.header.deadline_budget_ns, 5'000'000u);
  EXPECT_EQ(view.header.server_instance_id, "srv-1");
  EXPECT_EQ(view.header.schema_version.minor, 3);
  EvaluateRequestView ev;
  ASSERT_TRUE(decodeEvaluateRequest(view.body, ev).ok());
  EXPECT_EQ(ev.function_id, "abc");
  EXPECT_EQ(ev.knots, 1u);
  ASSERT_EQ(ev.inputs.size(), 3u);
  EXPECT_EQ(ev.inputs[2], 3.0);
  // The doubles are read in place: they lie inside the chunk.
  EXPECT_GE(reinterpret_cast<const void*>(ev.inputs.data()), chunk.data());

  // Truncated anywhere: INVALID_ARGUMENT.
  for (std::size_t cut = 0; cut < chunk.size; ++cut) {
    RequestView v;
    EvaluateRequestView e;
    Status s = parseRequest(chunk.data(), cut, v);
    if (s.ok()) s = decodeEvaluateRequest(v.body, e);
    EXPECT_EQ(s.code, StatusCode::InvalidArgument) << "cut at " << cut;
  }
  auto corrupt = [&](auto mutate) {
    Chunk copy = chunk;
    ChunkHeader h;
    std::memcpy(&h, copy.data(), sizeof h);
    mutate(h);
    std::memcpy(copy.data(), &h, sizeof h);
    RequestView v;
    EvaluateRequestView e;
    Status s = parseRequest(copy.data(), copy.size, v);
    if (s.ok()) s = decodeEvaluateRequest(v.body, e);
    return s;
  };
  EXPECT_EQ(corrupt([](ChunkHeader& h) { h.magic = 0; }).code, StatusCode::InvalidArgument);
  const Status unknown = corrupt([](ChunkHeader& h) { h.method = 77; });
  EXPECT_EQ(unknown.code, StatusCode::InvalidArgument);
  EXPECT_NE(unknown.message.find("unknown method 77"), std::string::npos) << unknown.message;
  EXPECT_EQ(corrupt([](ChunkHeader& h) { h.kind = 2; }).code, StatusCode::InvalidArgument);
  EXPECT_EQ(corrupt([](ChunkHeader& h) { h.body_length += 8; }).code, StatusCode::InvalidArgument);
  EXPECT_EQ(corrupt([](ChunkHeader& h) { h.body_length = ~0ull; }).code, StatusCode::InvalidArgument);
  EXPECT_EQ(corrupt([](ChunkHeader& h) { h.status_message_length = 0xFFFFFFF0u; }).code, StatusCode::InvalidArgument);
  EXPECT_EQ(corrupt([](ChunkHeader& h) { std::memset(h.client_id, 'x', sizeof h.client_id); }).code,
            StatusCode::InvalidArgument);
  EXPECT_EQ(corrupt([](ChunkHeader& h) { h.body_length -= 8; }).code, StatusCode::InvalidArgument);

  // Evaluate body lengths that lie.
  Chunk bad = chunk;
  EvaluateRequestFixed fixed;
  std::byte* b = bodyOf(bad.data());
  std::memcpy(&fixed, b, sizeof fixed);
  fixed.value_count = 1ull << 60;
  std::memcpy(b, &fixed, sizeof fixed);
  RequestView v;
  ASSERT_TRUE(parseRequest(bad.data(), bad.size, v).ok());
  EvaluateRequestView e;
  EXPECT_EQ(decodeEvaluateRequest(v.body, e).code, StatusCode::InvalidArgument);
  fixed.value_count = 3;
  fixed.function_id_length = 1000;
  std::memcpy(b, &fixed, sizeof fixed);
  EXPECT_EQ(decodeEvaluateRequest(v.body, e).code, StatusCode::InvalidArgument);
}

TEST(ShmCodec, ReplyChunkCarriesStatusAndBody) {
  rpc::ReplyHeader header;
  header.client_id = "c";
  header.server_instance_id = "s";
  header.correlation_id = 7;
  header.status = {StatusCode::NotFound, "no function 'x' (of 13 chars)"};
  const auto body = encode(rpc::ReleaseReply{3});
  Chunk chunk(chunkSize(wireMessage(header.status).size(), body.size()));
  writeReplyHeader(chunk.data(), header, rpc::Method::Release, body.size());
  std::memcpy(bodyOf(chunk.data()), body.data(), body.size());
  ReplyView view;
  ASSERT_TRUE(parseReply(chunk.data(), chunk.size, view).ok());
  EXPECT_EQ(view.method, rpc::Method::Release);
  EXPECT_EQ(view.header.status.code, StatusCode::NotFound);
  EXPECT_EQ(view.header.status.message, header.status.message);
  EXPECT_EQ(view.header.correlation_id, 7u);
  rpc::ReleaseReply r;
  ASSERT_TRUE(decode(view.body, r).ok());
  EXPECT_EQ(r.references_left, 3u);
  // A request parser refuses a reply chunk.
  RequestView request;
  EXPECT_EQ(parseRequest(chunk.data(), chunk.size, request).code, StatusCode::InvalidArgument);
  // Ids that do not fit are refused before writing.
  EXPECT_EQ(checkId("client id", std::string(64, 'a')).code, StatusCode::InvalidArgument);
  EXPECT_TRUE(checkId("client id", std::string(63, 'a')).ok());
}

// The session handshake's chunks: an open is not a request (and the reverse), and the
// reply carries the session's event only when the status is OK.
TEST(ShmCodec, SessionChunksRoundTripAndAreNotRequests) {
  std::vector<std::uint64_t> storage(64);
  void* chunk = storage.data();
  rpc::RequestHeader request;
  request.client_id = "host:1:abc";
  request.correlation_id = 7;
  writeSessionOpen(chunk, request);
  RequestView open;
  ASSERT_TRUE(parseSessionOpen(chunk, chunkSize(0, 0), open).ok());
  EXPECT_EQ(open.header.client_id, "host:1:abc");
  EXPECT_EQ(open.header.correlation_id, 7u);
  const Status not_request = parseRequest(chunk, chunkSize(0, 0), open);
  EXPECT_EQ(not_request.code, StatusCode::InvalidArgument);
  EXPECT_NE(not_request.message.find("session open"), std::string::npos) << not_request.message;

  rpc::ReplyHeader reply;
  reply.correlation_id = 7;
  writeSessionReply(chunk, reply, "rpc.1.0123456789abcdef");
  ReplyView view;
  ASSERT_TRUE(parseSessionReply(chunk, chunkSize(0, 22), view).ok());
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(view.body.data()), view.body.size()), "rpc.1.0123456789abcdef");
  EXPECT_FALSE(parseReply(chunk, chunkSize(0, 22), view).ok());

  reply.status = {StatusCode::ResourceExhausted, "full"};
  writeSessionReply(chunk, reply, "ignored");
  ASSERT_TRUE(parseSessionReply(chunk, chunkSize(wireMessage(reply.status).size(), 0), view).ok());
  EXPECT_EQ(view.header.status.code, StatusCode::ResourceExhausted);
  EXPECT_TRUE(view.body.empty());
}

TEST(ShmMempools, DeployRoudiTomlMatchesTheCompiledTable) {
  std::ifstream in(testing::sourceDir() / "deploy" / "roudi.toml");
  ASSERT_TRUE(in) << "deploy/roudi.toml missing";
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  const std::regex pool(R"(\[\[segment\.mempool\]\]\s*size\s*=\s*(\d+)\s*count\s*=\s*(\d+))");
  std::vector<Mempool> found;
  for (auto it = std::sregex_iterator(s.begin(), s.end(), pool); it != std::sregex_iterator(); ++it)
    found.push_back({static_cast<std::uint32_t>(std::stoul((*it)[1])), static_cast<std::uint32_t>(std::stoul((*it)[2]))});
  ASSERT_EQ(found.size(), kMempools.size());
  for (std::size_t i = 0; i < found.size(); ++i) {
    EXPECT_EQ(found[i].size, kMempools[i].size) << "pool " << i;
    EXPECT_EQ(found[i].count, kMempools[i].count) << "pool " << i;
  }
  // The largest batch the server accepts fits: 1000 knots x 3000 outputs.
  EXPECT_GE(maxChunkPayload(), chunkSize(0, evaluateReplyBodySize(1000ull * 3000)));
}

}  // namespace
}  // namespace robodiff::shm
