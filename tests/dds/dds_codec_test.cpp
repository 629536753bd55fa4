// The DDS codec without DDS: every message to the C types and back, field by field; the
// envelope discriminators; and the planning / assembling of EvaluateBatch chunks.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "robodiff/schema/dds_batch_chunks.hpp"
#include "robodiff/schema/dds_codec.hpp"

namespace robodiff {
namespace {

using namespace dds_codec;

// Request and reply bodies go through a whole owning sample, as on the wire path.
template <class Message>
Message viaRequest(const Message& in) {
  WireRequest sample;
  toWire(RequestBody(in), sample->body);
  RequestBody out;
  const Status status = fromWire(sample->body, out);
  EXPECT_TRUE(status.ok()) << status.message;
  return std::get<Message>(out);
}

template <class Message>
Message viaReply(const Message& in) {
  WireReply sample;
  toWire(ReplyBody(in), sample->body);
  ReplyBody out;
  const Status status = fromWire(sample->body, out);
  EXPECT_TRUE(status.ok()) << status.message;
  return std::get<Message>(out);
}

TEST(DdsCodec, RequestHeaderBothWays) {
  rpc::RequestHeader in;
  in.schema_version = {3, 9};
  in.client_id = "host:123:abcdef01";
  in.correlation_id = 0xfedcba9876543210ull;
  in.deadline_budget_ns = 2'500'000'000ull;
  in.server_instance_id = "robodiffd-7";
  WireRequest sample;
  toWire(in, sample->header);
  const rpc::RequestHeader out = fromWire(sample->header);
  EXPECT_EQ(out.schema_version.major, 3);
  EXPECT_EQ(out.schema_version.minor, 9);
  EXPECT_EQ(out.client_id, in.client_id);
  EXPECT_EQ(out.correlation_id, in.correlation_id);
  EXPECT_EQ(out.deadline_budget_ns, in.deadline_budget_ns);
  EXPECT_EQ(out.server_instance_id, in.server_instance_id);
}

TEST(DdsCodec, ReplyHeaderBothWaysAndUnknownCodes) {
  rpc::ReplyHeader in;
  in.schema_version = {1, 0};
  in.server_instance_id = "robodiffd-7";
  in.client_id = "";
  in.correlation_id = 42;
  in.status = {StatusCode::ResourceExhausted, "request queue full (3 waiting); retry later"};
  WireReply sample;
  toWire(in, sample->header);
  EXPECT_NE(sample->header.client_id, nullptr);  // empty strings are "" on the wire, not null
  rpc::ReplyHeader out = fromWire(sample->header);
  EXPECT_EQ(out.server_instance_id, in.server_instance_id);
  EXPECT_EQ(out.client_id, "");
  EXPECT_EQ(out.correlation_id, 42u);
  EXPECT_EQ(out.status.code, StatusCode::ResourceExhausted);
  EXPECT_EQ(out.status.message, in.status.message);
  sample->header.status.code = static_cast<robodiff_wire_StatusCode>(99);  // a newer peer's code
  EXPECT_EQ(fromWire(sample->header).status.code, StatusCode::Unknown);
}

TEST(DdsCodec, RequestBodiesBothWays) {
  const auto load = viaRequest(rpc::LoadModelRequest{"<robot name=\"r\">\xc3\xa4</robot>", true, R"({"a":1})"});
  EXPECT_EQ(load.urdf, "<robot name=\"r\">\xc3\xa4</robot>");
  EXPECT_TRUE(load.floating_base);
  EXPECT_EQ(load.options_json, R"({"a":1})");

  const auto get = viaRequest(rpc::GetFunctionRequest{"model-1", R"({"function":"rnea"})", true});
  EXPECT_EQ(get.model_id, "model-1");
  EXPECT_EQ(get.spec_json, R"({"function":"rnea"})");
  EXPECT_TRUE(get.wait);

  const std::vector<double> values = {1.5, -0.0, std::nextafter(1.0, 2.0), 1e-310,
                                      std::numeric_limits<double>::max()};
  const auto eval = viaRequest(rpc::EvaluateRequest{"fn-1", values});
  EXPECT_EQ(eval.function_id, "fn-1");
  ASSERT_EQ(eval.inputs.size(), values.size());
  EXPECT_EQ(std::memcmp(eval.inputs.data(), values.data(), values.size() * sizeof(double)), 0);

  const auto batch = viaRequest(rpc::EvaluateBatchRequest{"fn-2", 5, std::vector<double>(15, 0.25)});
  EXPECT_EQ(batch.function_id, "fn-2");
  EXPECT_EQ(batch.knot_count, 5u);
  EXPECT_EQ(batch.inputs, std::vector<double>(15, 0.25));

  const auto empty_batch = viaRequest(rpc::EvaluateBatchRequest{"fn-3", 0, {}});
  EXPECT_EQ(empty_batch.knot_count, 0u);
  EXPECT_TRUE(empty_batch.inputs.empty());

  EXPECT_EQ(viaRequest(rpc::ListFunctionsRequest{"model-9", 0, ""}).model_id, "model-9");
  const auto paged = viaRequest(rpc::ListFunctionsRequest{"model-9", 50, "page-7"});
  EXPECT_EQ(paged.page_size, 50u);
  EXPECT_EQ(paged.page_token, "page-7");
  EXPECT_TRUE(viaRequest(rpc::HealthRequest{true}).verbose);
  EXPECT_EQ(viaRequest(rpc::ReleaseRequest{"fn-9"}).id, "fn-9");
}

TEST(DdsCodec, ReplyBodiesBothWays) {
  const auto load = viaReply(rpc::LoadModelReply{"abc123", {"j1", "j2"}, {"f1", "", "f3"}, 7, 6});
  EXPECT_EQ(load.model_id, "abc123");
  EXPECT_EQ(load.joint_names, (std::vector<std::string>{"j1", "j2"}));
  EXPECT_EQ(load.frame_names, (std::vector<std::string>{"f1", "", "f3"}));
  EXPECT_EQ(load.nq, 7u);
  EXPECT_EQ(load.nv, 6u);

  rpc::GetFunctionReply function;
  function.function_id = "fn-1";
  function.state = rpc::FunctionState::Failed;
  function.inputs = {{"q", 7}, {"v", 6}};
  function.outputs = {{"value", rpc::OutputKind::Value, 6, 1, rpc::OutputLayout::DenseRowMajor, 6, {}, {}},
                      {"jac", rpc::OutputKind::Hessian, 3, 4, rpc::OutputLayout::SparseCsr, 5, {0, 2, 3, 5}, {0, 3, 1, 2, 3}}};
  const auto get = viaReply(function);
  EXPECT_EQ(get.function_id, "fn-1");
  EXPECT_EQ(get.state, rpc::FunctionState::Failed);
  ASSERT_EQ(get.inputs.size(), 2u);
  EXPECT_EQ(get.inputs[1].name, "v");
  EXPECT_EQ(get.inputs[1].size, 6u);
  ASSERT_EQ(get.outputs.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto &a = get.outputs[i], &b = function.outputs[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.rows, b.rows);
    EXPECT_EQ(a.cols, b.cols);
    EXPECT_EQ(a.layout, b.layout);
    EXPECT_EQ(a.nnz, b.nnz);
    EXPECT_EQ(a.row_offsets, b.row_offsets);
    EXPECT_EQ(a.col_indices, b.col_indices);
  }

  EXPECT_EQ(viaReply(rpc::EvaluateReply{{1, 2, 3}}).outputs, (std::vector<double>{1, 2, 3}));

  const auto chunk = viaReply(rpc::EvaluateBatchReply{1, 3, 10, 4, 4, std::vector<double>(12, -1.0)});
  EXPECT_EQ(chunk.chunk_index, 1u);
  EXPECT_EQ(chunk.chunk_count, 3u);
  EXPECT_EQ(chunk.total_knots, 10u);
  EXPECT_EQ(chunk.first_knot, 4u);
  EXPECT_EQ(chunk.knot_count, 4u);
  EXPECT_EQ(chunk.outputs, std::vector<double>(12, -1.0));

  rpc::ListFunctionsReply list;
  list.functions = {{"fn-1", "m-1", "rnea", rpc::FunctionState::Ready, true, 123456789012ull, ""},
                    {"fn-2", "m-1", "aba", rpc::FunctionState::Building, false, 0, "queued"}};
  list.next_page_token = "17";
  list.total = 300;
  const auto listed = viaReply(list);
  EXPECT_EQ(listed.next_page_token, "17");
  EXPECT_EQ(listed.total, 300u);
  ASSERT_EQ(listed.functions.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto &a = listed.functions[i], &b = list.functions[i];
    EXPECT_EQ(a.function_id, b.function_id);
    EXPECT_EQ(a.model_id, b.model_id);
    EXPECT_EQ(a.function_name, b.function_name);
    EXPECT_EQ(a.state, b.state);
    EXPECT_EQ(a.compiled, b.compiled);
    EXPECT_EQ(a.evaluations, b.evaluations);
    EXPECT_EQ(a.message, b.message);
  }

  rpc::HealthReply health;
  health.state = rpc::ServingState::Draining;
  health.version = "0.1.0";
  health.server_instance_id = "robodiffd-7";
  health.uptime_ns = 1ull << 50;
  health.models_loaded = 1, health.functions_loaded = 2, health.functions_compiled = 3;
  health.builds_queued = 4, health.builds_running = 5, health.builds_failed = 6, health.builds_done = 7;
  health.cache_hits = 8, health.cache_misses = 9, health.cache_bytes = 10, health.cache_entries = 11;
  health.workers_total = 12, health.workers_busy = 13, health.queue_depth = 14, health.queue_capacity = 15;
  health.batch_threads = 16;
  health.methods = {{rpc::Method::Release, 1, 2, 3, 4, 5, 6}, {rpc::Method::Evaluate, 7, 8, 9, 10, 11, 12}};
  health.errors = {{StatusCode::DataLoss, 17}};
  health.transports = {{"dds", 18, 19}};
  const auto h = viaReply(health);
  EXPECT_EQ(h.state, rpc::ServingState::Draining);
  EXPECT_EQ(h.version, "0.1.0");
  EXPECT_EQ(h.server_instance_id, "robodiffd-7");
  EXPECT_EQ(h.uptime_ns, 1ull << 50);
  EXPECT_EQ(h.models_loaded + h.functions_loaded + h.functions_compiled, 6u);
  EXPECT_EQ(h.builds_queued, 4u);
  EXPECT_EQ(h.builds_running, 5u);
  EXPECT_EQ(h.builds_failed, 6u);
  EXPECT_EQ(h.builds_done, 7u);
  EXPECT_EQ(h.cache_hits, 8u);
  EXPECT_EQ(h.cache_misses, 9u);
  EXPECT_EQ(h.cache_bytes, 10u);
  EXPECT_EQ(h.cache_entries, 11u);
  EXPECT_EQ(h.workers_total, 12u);
  EXPECT_EQ(h.workers_busy, 13u);
  EXPECT_EQ(h.queue_depth, 14u);
  EXPECT_EQ(h.queue_capacity, 15u);
  EXPECT_EQ(h.batch_threads, 16u);
  ASSERT_EQ(h.methods.size(), 2u);
  EXPECT_EQ(h.methods[1].method, rpc::Method::Evaluate);
  EXPECT_EQ(h.methods[1].requests, 7u);
  EXPECT_EQ(h.methods[1].errors, 8u);
  EXPECT_EQ(h.methods[1].p50_ns, 9u);
  EXPECT_EQ(h.methods[1].p90_ns, 10u);
  EXPECT_EQ(h.methods[1].p99_ns, 11u);
  EXPECT_EQ(h.methods[1].max_ns, 12u);
  ASSERT_EQ(h.errors.size(), 1u);
  EXPECT_EQ(h.errors[0].code, StatusCode::DataLoss);
  EXPECT_EQ(h.errors[0].count, 17u);
  ASSERT_EQ(h.transports.size(), 1u);
  EXPECT_EQ(h.transports[0].transport, "dds");
  EXPECT_EQ(h.transports[0].requests, 18u);
  EXPECT_EQ(h.transports[0].errors, 19u);

  EXPECT_EQ(viaReply(rpc::ReleaseReply{3}).references_left, 3u);
}

TEST(DdsCodec, JobMessagesBothWays) {
  const auto submit = viaRequest(rpc::SubmitJobRequest{"trajectory", R"({"data": "t.csv"})"});
  EXPECT_EQ(submit.kind, "trajectory");
  EXPECT_EQ(submit.params_json, R"({"data": "t.csv"})");
  EXPECT_EQ(viaRequest(rpc::JobStatusRequest{"job-1"}).job_id, "job-1");
  EXPECT_EQ(viaRequest(rpc::CancelJobRequest{"job-2"}).job_id, "job-2");
  EXPECT_EQ(viaRequest(rpc::JobResultRequest{"job-3"}).job_id, "job-3");
  EXPECT_EQ(viaReply(rpc::SubmitJobReply{"job-4"}).job_id, "job-4");
  EXPECT_EQ(viaReply(rpc::CancelJobReply{rpc::JobState::Running}).state, rpc::JobState::Running);

  rpc::JobInfo info{"job-5", "identify", rpc::JobState::Failed, 0.25, 12.5, -1.0, {"stacking", "qr"}, "worker crashed"};
  rpc::JobStatusReply status;
  status.jobs = {info, rpc::JobInfo{}};
  const auto got = viaReply(status);
  ASSERT_EQ(got.jobs.size(), 2u);
  EXPECT_EQ(got.jobs[0].job_id, "job-5");
  EXPECT_EQ(got.jobs[0].kind, "identify");
  EXPECT_EQ(got.jobs[0].state, rpc::JobState::Failed);
  EXPECT_EQ(got.jobs[0].progress, 0.25);
  EXPECT_EQ(got.jobs[0].elapsed_seconds, 12.5);
  EXPECT_EQ(got.jobs[0].eta_seconds, -1.0);
  EXPECT_EQ(got.jobs[0].messages, (std::vector<std::string>{"stacking", "qr"}));
  EXPECT_EQ(got.jobs[0].error, "worker crashed");
  EXPECT_EQ(got.jobs[1].state, rpc::JobState::Queued);

  rpc::JobResultReply result{info, R"({"knots": 3})", "/var/cache/robodiff/jobs/job-5"};
  const auto r = viaReply(result);
  EXPECT_EQ(r.info.messages, info.messages);
  EXPECT_EQ(r.result_json, R"({"knots": 3})");
  EXPECT_EQ(r.result_dir, "/var/cache/robodiff/jobs/job-5");
}

// Bytes as they come out of a file: zeros, 0xff, every value between.
std::vector<std::uint8_t> ddsCodecTestBytes() {
  std::vector<std::uint8_t> bytes = {0x00, 0xff, 0x00, 0x00, 0x7f, 0x80, 0xff};
  for (int i = 0; i < 256; ++i) bytes.push_back(static_cast<std::uint8_t>(255 - i));
  return bytes;
}

TEST(DdsCodec, ArtifactMessagesBothWays) {
  const auto query = viaRequest(rpc::QueryArtifactRequest{"pk-1", "<robot name=\"a\"/>", true,
                                                          R"({"build": {"target": "x86-64-v3"}})", true, false});
  EXPECT_EQ(query.portable_key, "pk-1");
  EXPECT_EQ(query.urdf, "<robot name=\"a\"/>");
  EXPECT_TRUE(query.floating_base);
  EXPECT_EQ(query.spec_json, R"({"build": {"target": "x86-64-v3"}})");
  EXPECT_TRUE(query.build);
  EXPECT_FALSE(query.include_sources);

  const auto have = viaReply(rpc::QueryArtifactReply{rpc::ArtifactState::Have, "key-9", R"({"files": []})",
                                                     std::string(128, 'a'), 1ull << 33, 4, "none"});
  EXPECT_EQ(have.state, rpc::ArtifactState::Have);
  EXPECT_EQ(have.key, "key-9");
  EXPECT_EQ(have.manifest_json, R"({"files": []})");
  EXPECT_EQ(have.signature_hex, std::string(128, 'a'));
  EXPECT_EQ(have.payload_bytes, 1ull << 33);
  EXPECT_EQ(have.builds_queued, 4u);
  EXPECT_EQ(have.message, "none");
  rpc::QueryArtifactReply failed;
  failed.state = rpc::ArtifactState::Failed;
  failed.message = "the compiler ran out of memory";
  const auto failed_back = viaReply(failed);
  EXPECT_EQ(failed_back.state, rpc::ArtifactState::Failed);
  EXPECT_EQ(failed_back.message, "the compiler ran out of memory");

  const auto fetch = viaRequest(rpc::FetchArtifactChunkRequest{"key-9", true, (1ull << 32) + 5, 65536});
  EXPECT_EQ(fetch.key, "key-9");
  EXPECT_TRUE(fetch.include_sources);
  EXPECT_EQ(fetch.offset, (1ull << 32) + 5);
  EXPECT_EQ(fetch.max_bytes, 65536u);

  const std::vector<std::uint8_t> bytes = ddsCodecTestBytes();
  const auto chunk = viaReply(rpc::FetchArtifactChunkReply{7, 263, bytes});
  EXPECT_EQ(chunk.offset, 7u);
  EXPECT_EQ(chunk.payload_bytes, 263u);
  EXPECT_EQ(chunk.data, bytes);  // zeros do not end it, 0xff stays 0xff
  const auto end = viaReply(rpc::FetchArtifactChunkReply{263, 263, {}});
  EXPECT_TRUE(end.data.empty());
  EXPECT_EQ(end.offset, 263u);
}

TEST(DdsCodec, ArtifactBytesAreAnOctetSequenceOnTheWire) {
  WireReply sample;
  toWire(ReplyBody(rpc::FetchArtifactChunkReply{0, 3, {0x00, 0xff, 0x01}}), sample->body);
  EXPECT_EQ(sample->body._d, robodiff_wire_METHOD_FETCH_ARTIFACT_CHUNK);
  const auto& data = sample->body._u.fetch_artifact_chunk.data;
  ASSERT_EQ(data._length, 3u);
  EXPECT_EQ(data._buffer[0], 0x00);
  EXPECT_EQ(data._buffer[1], 0xff);
  EXPECT_EQ(data._buffer[2], 0x01);
  EXPECT_TRUE(data._release);  // owned by the sample, freed with it
}

TEST(DdsCodec, FleetStatusBothWays) {
  EXPECT_TRUE(viaRequest(rpc::FleetStatusRequest{true}).verbose);
  rpc::FleetStatusReply in;
  in.fleet = {"robot", "x86-64-v3", 11, 1ull << 35, 2, 3, 0, 0, 0, {}};
  in.fleet.peers = {{"build-a", "robodiffd-1", true, 10, 1ull << 34, 1, 0, 0.75, "signature by an untrusted key"},
                    {"build-b", "", false, 0, 0, 0, 5, 0.0, "no answer within 2 s"}};
  const rpc::FleetFigures f = viaReply(in).fleet;
  EXPECT_EQ(f.role, "robot");
  EXPECT_EQ(f.target, "x86-64-v3");
  EXPECT_EQ(f.artifacts_fetched, 11u);
  EXPECT_EQ(f.bytes_fetched, 1ull << 35);
  EXPECT_EQ(f.artifacts_refused, 2u);
  EXPECT_EQ(f.fetch_failures, 3u);
  ASSERT_EQ(f.peers.size(), 2u);
  EXPECT_EQ(f.peers[0].service, "build-a");
  EXPECT_EQ(f.peers[0].instance_id, "robodiffd-1");
  EXPECT_TRUE(f.peers[0].reachable);
  EXPECT_EQ(f.peers[0].artifacts_fetched, 10u);
  EXPECT_EQ(f.peers[0].bytes_fetched, 1ull << 34);
  EXPECT_EQ(f.peers[0].refusals, 1u);
  EXPECT_EQ(f.peers[0].last_problem, "signature by an untrusted key");
  EXPECT_FALSE(f.peers[1].reachable);
  EXPECT_EQ(f.peers[1].instance_id, "");
  EXPECT_EQ(f.peers[1].failures, 5u);

  rpc::FleetStatusReply build;
  build.fleet.role = "build";
  build.fleet.artifacts_served = 6;
  build.fleet.bytes_served = 7;
  build.fleet.builds_for_robots = 8;
  const rpc::FleetFigures b = viaReply(build).fleet;
  EXPECT_EQ(b.role, "build");
  EXPECT_EQ(b.artifacts_served, 6u);
  EXPECT_EQ(b.bytes_served, 7u);
  EXPECT_EQ(b.builds_for_robots, 8u);
  EXPECT_TRUE(b.peers.empty());
}

TEST(DdsCodec, DiscriminatorIsTheMethod) {
  WireRequest sample;
  toWire(RequestBody(rpc::ReleaseRequest{"x"}), sample->body);
  EXPECT_EQ(sample->body._d, robodiff_wire_METHOD_RELEASE);
  EXPECT_EQ(methodFromWire(sample->body._d), rpc::Method::Release);
}

// A non-OK reply's empty body is the method's own, for every method (a new one included).
TEST(DdsCodec, EveryMethodsEmptyReplyCarriesItsDiscriminator) {
  for (std::uint32_t m = 0; m < rpc::kMethodCount; ++m) {
    const ReplyBody body = emptyReplyBody(static_cast<rpc::Method>(m));
    EXPECT_EQ(body.index(), m) << rpc::toString(static_cast<rpc::Method>(m));
    WireReply sample;
    toWire(body, sample->body);
    EXPECT_EQ(static_cast<std::uint32_t>(sample->body._d), m);
    ReplyBody back;
    ASSERT_TRUE(fromWire(sample->body, back).ok());
    EXPECT_EQ(back.index(), m);
  }
}

TEST(DdsCodec, UnknownDiscriminatorIsInvalidArgument) {
  robodiff_wire_RequestBody body{};
  body._d = static_cast<robodiff_wire_Method>(77);
  RequestBody out;
  const Status status = fromWire(body, out);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("77"), std::string::npos) << status.message;
  robodiff_wire_ReplyBody reply{};
  reply._d = static_cast<robodiff_wire_Method>(rpc::kMethodCount);
  ReplyBody reply_out;
  EXPECT_EQ(fromWire(reply, reply_out).code, StatusCode::InvalidArgument);
}

TEST(DdsCodec, NullStringsAndSequencesReadAsEmpty) {
  robodiff_wire_LoadModelReply in{};  // all null, as a malformed or zeroed sample could be
  rpc::LoadModelReply out;
  fromWire(in, out);
  EXPECT_EQ(out.model_id, "");
  EXPECT_TRUE(out.joint_names.empty());
}

TEST(DdsCodec, BorrowedDoublesAreDetachedNotFreed) {
  std::vector<double> mine = {1, 2, 3};
  {
    WireRequest sample;
    sample->body._d = robodiff_wire_METHOD_EVALUATE;
    sample->body._u.evaluate.function_id = dupString("fn");
    borrowDoubles(sample->body._u.evaluate.inputs, mine);
    EXPECT_EQ(view(sample->body._u.evaluate.inputs).size(), 3u);
    detachDoubles(sample->body._u.evaluate.inputs);
  }  // freeing the sample must leave `mine` alone
  EXPECT_EQ(mine[2], 3.0);
}

// ---- EvaluateBatch chunks ----------------------------------------------------------------

TEST(DdsBatchChunks, PlanKeepsEachChunkUnderTheLimit) {
  const ChunkPlan plan = planBatchChunks(100, 3, 5 * 3 * sizeof(double));
  EXPECT_EQ(plan.knots_per_chunk, 5u);
  EXPECT_EQ(plan.chunk_count, 20u);
  const ChunkPlan uneven = planBatchChunks(11, 3, 4 * 3 * sizeof(double));
  EXPECT_EQ(uneven.chunk_count, 3u);
  EXPECT_EQ(uneven.firstKnot(2), 8u);
  EXPECT_EQ(uneven.knotCount(2, 11), 3u);
  EXPECT_EQ(planBatchChunks(10, 1000, 8).knots_per_chunk, 1u);  // a knot larger than the limit
  EXPECT_EQ(planBatchChunks(0, 3, 1024).chunk_count, 1u);
  EXPECT_EQ(planBatchChunks(7, 3, 1 << 20).chunk_count, 1u);
}

TEST(DdsBatchChunks, AssemblerPutsChunksInPlaceInAnyOrder) {
  std::vector<double> outputs(4 * 2, 0.0);
  BatchAssembler assembler(4, outputs);
  std::vector<double> second = {5, 6, 7, 8}, first = {1, 2, 3, 4};
  robodiff_wire_EvaluateBatchReply chunk{};
  chunk.chunk_count = 2;
  chunk.total_knots = 4;
  chunk.chunk_index = 1;
  chunk.first_knot = 2;
  chunk.knot_count = 2;
  borrowDoubles(chunk.outputs, second);
  ASSERT_TRUE(assembler.add(chunk).ok());
  EXPECT_FALSE(assembler.complete());
  const Status twice = assembler.add(chunk);
  EXPECT_EQ(twice.code, StatusCode::Internal);
  chunk.chunk_index = 0;
  chunk.first_knot = 0;
  borrowDoubles(chunk.outputs, first);
  ASSERT_TRUE(assembler.add(chunk).ok());
  EXPECT_TRUE(assembler.complete());
  EXPECT_EQ(outputs, (std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8}));
}

TEST(DdsBatchChunks, AssemblerRejectsChunksThatDoNotFit) {
  std::vector<double> outputs(6);
  std::vector<double> values(4);
  robodiff_wire_EvaluateBatchReply chunk{};
  chunk.chunk_count = 1;
  chunk.total_knots = 3;
  chunk.knot_count = 2;
  chunk.first_knot = 2;  // knots 2..3 of 3
  borrowDoubles(chunk.outputs, values);
  EXPECT_EQ(BatchAssembler(3, outputs).add(chunk).code, StatusCode::Internal);
  chunk.first_knot = 0;
  chunk.total_knots = 5;  // not the request's
  EXPECT_EQ(BatchAssembler(3, outputs).add(chunk).code, StatusCode::Internal);
  chunk.total_knots = 3;
  chunk.knot_count = 1;  // 4 doubles for 1 knot of 2
  EXPECT_EQ(BatchAssembler(3, outputs).add(chunk).code, StatusCode::Internal);
}

}  // namespace
}  // namespace robodiff
