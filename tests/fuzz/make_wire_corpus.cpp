// Writes the seed corpora of the two wire-codec fuzz targets: one valid encoding of every
// request and reply, in the input format of shm_wire_fuzz.cpp and dds_wire_fuzz.cpp.
//
//   fuzz_make_wire_corpus OUT_DIR     -> OUT_DIR/shm_wire/*.bin, OUT_DIR/dds_wire/*.bin
//
// The files in tests/fuzz/corpus/ were made with it; run it again when the wire types change.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <dds/ddsi/ddsi_cdrstream.h>

#include "robodiff/schema/dds_codec.hpp"
#include "robodiff/schema/shm_codec.hpp"

namespace {

namespace rpc = robodiff::rpc;
namespace shm = robodiff::shm;
namespace codec = robodiff::dds_codec;

void writeFile(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(bytes.size()));
}

rpc::RequestHeader requestHeader() {
  rpc::RequestHeader h;
  h.client_id = "fuzz-client-1";
  h.correlation_id = 7;
  h.deadline_budget_ns = 1'000'000'000;
  return h;
}

rpc::ReplyHeader replyHeader() {
  rpc::ReplyHeader h;
  h.server_instance_id = "robodiffd-fuzz";
  h.client_id = "fuzz-client-1";
  h.correlation_id = 7;
  return h;
}

// ---- the messages ---------------------------------------------------------------------

rpc::JobInfo jobInfo() {
  rpc::JobInfo info;
  info.job_id = "job-1";
  info.kind = "trajectory";
  info.state = rpc::JobState::Running;
  info.progress = 0.5;
  info.messages = {"started", "half way"};
  return info;
}

rpc::GetFunctionReply functionReply() {
  rpc::GetFunctionReply r;
  r.function_id = "f-1";
  r.state = rpc::FunctionState::Ready;
  r.inputs = {{"q", 3}, {"v", 3}};
  rpc::OutputBlock dense{"tau", rpc::OutputKind::Value, 3, 1, rpc::OutputLayout::DenseRowMajor, 3, {}, {}};
  rpc::OutputBlock sparse{"J", rpc::OutputKind::Jacobian, 2, 2, rpc::OutputLayout::SparseCsr, 2, {0, 1, 2}, {0, 1}};
  r.outputs = {dense, sparse};
  return r;
}

rpc::FleetStatusReply fleetReply() {
  rpc::FleetStatusReply r;
  r.fleet.role = "robot";
  r.fleet.target = "x86-64-v3";
  r.fleet.artifacts_fetched = 2;
  r.fleet.bytes_fetched = 4096;
  r.fleet.peers = {{"build-a", "robodiffd-b", true, 2, 4096, 1, 0, 0.5, "signature by an untrusted key"}};
  return r;
}

rpc::HealthReply healthReply() {
  rpc::HealthReply r;
  r.state = rpc::ServingState::Serving;
  r.version = "0.1.0";
  r.server_instance_id = "robodiffd-fuzz";
  r.methods = {{rpc::Method::Evaluate, 10, 1, 5, 6, 7, 8}};
  r.errors = {{robodiff::StatusCode::InvalidArgument, 1}};
  r.transports = {{"iceoryx", 10, 1}};
  return r;
}

// ---- iceoryx chunks and bodies --------------------------------------------------------

template <class Message>
void shmRequest(const std::filesystem::path& dir, const std::string& name, rpc::Method method, const Message& m) {
  const std::vector<std::byte> body = shm::encode(m);
  std::vector<std::uint8_t> chunk(shm::chunkSize(0, body.size()));
  shm::writeRequestHeader(chunk.data(), requestHeader(), method, body.size());
  std::memcpy(shm::bodyOf(chunk.data()), body.data(), body.size());
  chunk.insert(chunk.begin(), 0);  // mode: a whole chunk
  writeFile(dir / ("request_" + name + ".bin"), chunk);
  std::vector<std::uint8_t> alone = {1, static_cast<std::uint8_t>(static_cast<unsigned>(method) << 1)};
  for (std::byte b : body) alone.push_back(static_cast<std::uint8_t>(b));
  writeFile(dir / ("request_body_" + name + ".bin"), alone);
}

template <class Message>
void shmReply(const std::filesystem::path& dir, const std::string& name, rpc::Method method, const Message& m) {
  const std::vector<std::byte> body = shm::encode(m);
  const robodiff::Status status{robodiff::StatusCode::Ok, ""};
  std::vector<std::uint8_t> chunk(shm::chunkSize(shm::wireMessage(status).size(), body.size()));
  rpc::ReplyHeader header = replyHeader();
  header.status = status;
  shm::writeReplyHeader(chunk.data(), header, method, body.size());
  std::memcpy(shm::bodyOf(chunk.data()), body.data(), body.size());
  chunk.insert(chunk.begin(), 0);
  writeFile(dir / ("reply_" + name + ".bin"), chunk);
  std::vector<std::uint8_t> alone = {1, static_cast<std::uint8_t>((static_cast<unsigned>(method) << 1) | 1)};
  for (std::byte b : body) alone.push_back(static_cast<std::uint8_t>(b));
  writeFile(dir / ("reply_body_" + name + ".bin"), alone);
}

// ---- DDS samples ----------------------------------------------------------------------

template <class T>
std::vector<std::uint8_t> cdr(const codec::WireSample<T>& sample, std::uint8_t selector) {
  dds_ostream_t os;
  dds_ostream_init(&os, 0, 1);  // XCDR1: every type is @final
  dds_stream_write(&os, reinterpret_cast<const char*>(&sample.get()), codec::WireDescriptor<T>::get()->m_ops);
  std::vector<std::uint8_t> bytes = {selector};
  bytes.insert(bytes.end(), os.m_buffer, os.m_buffer + os.m_index);
  dds_ostream_fini(&os);
  return bytes;
}

void ddsRequest(const std::filesystem::path& dir, const std::string& name, const codec::RequestBody& body) {
  codec::WireRequest sample;
  codec::toWire(requestHeader(), sample->header);
  codec::toWire(body, sample->body);
  writeFile(dir / ("request_" + name + ".bin"), cdr(sample, 0));
}

void ddsReply(const std::filesystem::path& dir, const std::string& name, const codec::ReplyBody& body) {
  codec::WireReply sample;
  codec::toWire(replyHeader(), sample->header);
  codec::toWire(body, sample->body);
  writeFile(dir / ("reply_" + name + ".bin"), cdr(sample, 4));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 2;
  }
  const std::filesystem::path out = argv[1];
  const auto s = out / "shm_wire";
  const auto d = out / "dds_wire";
  const rpc::LoadModelRequest load{"<robot name=\"r\"><link name=\"a\"/></robot>", true, "{\"source_name\": \"r\"}"};
  const rpc::GetFunctionRequest get{"model-1", "{\"function\": \"rnea\"}", true};
  const rpc::EvaluateRequest evaluate{"f-1", {0.1, 0.2, 0.3}};
  const rpc::EvaluateBatchRequest batch{"f-1", 2, {0.1, 0.2, 0.3, 0.4}};
  const rpc::ListFunctionsRequest list{"model-1", 10, "page-2"};
  const rpc::LoadModelReply loaded{"model-1", {"j1", "j2"}, {"base", "tool"}, 2, 2};
  const rpc::EvaluateReply evaluated{{1.0, -2.0}};
  const rpc::EvaluateBatchReply batched{0, 2, 4, 0, 2, {1.0, 2.0, 3.0, 4.0}};
  const rpc::ListFunctionsReply listed{{{"f-1", "model-1", "rnea", rpc::FunctionState::Failed, false, 3, "why"}}, "next", 5};
  const rpc::QueryArtifactRequest query{"pk-1", "<robot name=\"r\"/>", false, "{\"function\": \"rnea\"}", true, false};
  const rpc::QueryArtifactReply queried{rpc::ArtifactState::Have, "key-1", "{\"files\": []}", "ab12", 6, 0, ""};
  const rpc::FetchArtifactChunkRequest fetch{"key-1", false, 0, 4};
  const rpc::FetchArtifactChunkReply fetched{0, 6, {0x7f, 0x45, 0x00, 0xff}};

  shmRequest(s, "load_model", rpc::Method::LoadModel, load);
  shmRequest(s, "get_function", rpc::Method::GetFunction, get);
  shmRequest(s, "evaluate", rpc::Method::Evaluate, evaluate);
  shmRequest(s, "evaluate_batch", rpc::Method::EvaluateBatch, batch);
  shmRequest(s, "list_functions", rpc::Method::ListFunctions, list);
  shmRequest(s, "health", rpc::Method::Health, rpc::HealthRequest{true});
  shmRequest(s, "release", rpc::Method::Release, rpc::ReleaseRequest{"f-1"});
  shmRequest(s, "submit_job", rpc::Method::SubmitJob, rpc::SubmitJobRequest{"trajectory", "{\"urdf\": \"a.urdf\"}"});
  shmRequest(s, "job_status", rpc::Method::JobStatus, rpc::JobStatusRequest{"job-1"});
  shmRequest(s, "cancel_job", rpc::Method::CancelJob, rpc::CancelJobRequest{"job-1"});
  shmRequest(s, "job_result", rpc::Method::JobResult, rpc::JobResultRequest{"job-1"});
  shmRequest(s, "query_artifact", rpc::Method::QueryArtifact, query);
  shmRequest(s, "fetch_artifact_chunk", rpc::Method::FetchArtifactChunk, fetch);
  shmRequest(s, "fleet_status", rpc::Method::FleetStatus, rpc::FleetStatusRequest{true});
  shmReply(s, "load_model", rpc::Method::LoadModel, loaded);
  shmReply(s, "get_function", rpc::Method::GetFunction, functionReply());
  shmReply(s, "evaluate", rpc::Method::Evaluate, evaluated);
  shmReply(s, "evaluate_batch", rpc::Method::EvaluateBatch, batched);
  shmReply(s, "list_functions", rpc::Method::ListFunctions, listed);
  shmReply(s, "health", rpc::Method::Health, healthReply());
  shmReply(s, "release", rpc::Method::Release, rpc::ReleaseReply{2});
  shmReply(s, "submit_job", rpc::Method::SubmitJob, rpc::SubmitJobReply{"job-1"});
  shmReply(s, "job_status", rpc::Method::JobStatus, rpc::JobStatusReply{{jobInfo()}});
  shmReply(s, "cancel_job", rpc::Method::CancelJob, rpc::CancelJobReply{rpc::JobState::Cancelled});
  shmReply(s, "job_result", rpc::Method::JobResult, rpc::JobResultReply{jobInfo(), "{}", "/tmp/job-1"});
  shmReply(s, "query_artifact", rpc::Method::QueryArtifact, queried);
  shmReply(s, "fetch_artifact_chunk", rpc::Method::FetchArtifactChunk, fetched);
  shmReply(s, "fleet_status", rpc::Method::FleetStatus, fleetReply());

  ddsRequest(d, "load_model", load);
  ddsRequest(d, "get_function", get);
  ddsRequest(d, "evaluate", evaluate);
  ddsRequest(d, "evaluate_batch", batch);
  ddsRequest(d, "list_functions", list);
  ddsRequest(d, "health", rpc::HealthRequest{true});
  ddsRequest(d, "release", rpc::ReleaseRequest{"f-1"});
  ddsRequest(d, "submit_job", rpc::SubmitJobRequest{"trajectory", "{\"urdf\": \"a.urdf\"}"});
  ddsRequest(d, "job_status", rpc::JobStatusRequest{"job-1"});
  ddsRequest(d, "cancel_job", rpc::CancelJobRequest{"job-1"});
  ddsRequest(d, "job_result", rpc::JobResultRequest{"job-1"});
  ddsRequest(d, "query_artifact", query);
  ddsRequest(d, "fetch_artifact_chunk", fetch);
  ddsRequest(d, "fleet_status", rpc::FleetStatusRequest{true});
  ddsReply(d, "load_model", loaded);
  ddsReply(d, "get_function", functionReply());
  ddsReply(d, "evaluate", evaluated);
  ddsReply(d, "evaluate_batch", batched);
  ddsReply(d, "list_functions", listed);
  ddsReply(d, "health", healthReply());
  ddsReply(d, "release", rpc::ReleaseReply{2});
  ddsReply(d, "submit_job", rpc::SubmitJobReply{"job-1"});
  ddsReply(d, "job_status", rpc::JobStatusReply{{jobInfo()}});
  ddsReply(d, "cancel_job", rpc::CancelJobReply{rpc::JobState::Cancelled});
  ddsReply(d, "job_result", rpc::JobResultReply{jobInfo(), "{}", "/tmp/job-1"});
  ddsReply(d, "query_artifact", queried);
  ddsReply(d, "fetch_artifact_chunk", fetched);
  ddsReply(d, "fleet_status", fleetReply());
  std::printf("wrote %s and %s\n", s.c_str(), d.c_str());
  return 0;
}
