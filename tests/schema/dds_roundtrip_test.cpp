// A real Cyclone DDS round trip of the wire envelopes over loopback, between two
// processes: the child writes a LoadModel and an EvaluateBatch request, the parent reads
// them and answers with a GetFunction reply (dense + sparse blocks) and a chunk of an
// EvaluateBatch reply, which the child reads. Every field is compared on both sides.
// Configuration: deploy/cyclonedds-loopback.xml through CYCLONEDDS_URI.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <string>
#include <thread>
#include <vector>

#include <dds/dds.h>

#include "robodiff.h"  // idlc's C types of build/schema/robodiff.idl
#include "robodiff/schema/status.hpp"
#include "support/dds_domain.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kTimeout = std::chrono::seconds(8);  // per phase; generous for a loaded machine

// ---- building samples ----------------------------------------------------------------

// Keeps the memory the C samples point into.
struct Arena {
  std::deque<std::string> strings;
  std::deque<std::vector<double>> doubles;
  std::deque<std::vector<uint32_t>> uints;
  std::deque<std::vector<char*>> string_lists;
  std::deque<std::vector<robodiff_wire_InputBlock>> inputs;
  std::deque<std::vector<robodiff_wire_OutputBlock>> outputs;

  char* str(std::string s) { return strings.emplace_back(std::move(s)).data(); }
  template <class Seq, class T>
  static Seq seq(std::vector<T>& v) {
    Seq s{};
    s._maximum = s._length = static_cast<uint32_t>(v.size());
    s._buffer = v.data();
    s._release = false;
    return s;
  }
};

robodiff_wire_RequestHeader requestHeader(Arena& a, uint64_t correlation_id) {
  robodiff_wire_RequestHeader h{};
  h.schema_version = {kSchemaVersionMajor, kSchemaVersionMinor};
  h.client_id = a.str("schema-test-client/" + std::to_string(correlation_id));
  h.correlation_id = correlation_id;
  h.deadline_budget_ns = 250'000'000ull * correlation_id;
  h.server_instance_id = a.str(correlation_id % 2 ? "" : "robodiffd-7");
  return h;
}

robodiff_wire_Request loadModelRequest(Arena& a) {
  robodiff_wire_Request r{};
  r.header = requestHeader(a, 0x0123456789abcdefull);
  r.body._d = robodiff_wire_METHOD_LOAD_MODEL;
  std::string urdf = "<robot name=\"two_link\">\n";
  for (int i = 0; i < 50; ++i) urdf += "  <link name=\"link" + std::to_string(i) + "\"/> <!-- äöü -->\n";
  urdf += "</robot>\n";
  r.body._u.load_model.urdf = a.str(urdf);
  r.body._u.load_model.floating_base = true;
  r.body._u.load_model.options_json = a.str(R"({"gravity":[0,0,-9.81]})");
  return r;
}

constexpr uint32_t kKnots = 200, kInputsPerKnot = 21, kOutputsPerKnot = 29;

robodiff_wire_Request evaluateBatchRequest(Arena& a) {
  robodiff_wire_Request r{};
  r.header = requestHeader(a, 42);
  r.body._d = robodiff_wire_METHOD_EVALUATE_BATCH;
  auto& in = a.doubles.emplace_back(kKnots * kInputsPerKnot);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = std::sin(0.37 * double(i)) * 1e3 + 1e-12 * double(i);
  in[7] = -0.0;
  in[8] = std::nextafter(1.0, 2.0);
  r.body._u.evaluate_batch.function_id = a.str("fn-5f3a9c");
  r.body._u.evaluate_batch.knot_count = kKnots;
  r.body._u.evaluate_batch.inputs = Arena::seq<dds_sequence_double>(in);
  return r;
}

robodiff_wire_ReplyHeader replyHeader(Arena& a, uint64_t correlation_id, robodiff_wire_StatusCode code,
                                      std::string message) {
  robodiff_wire_ReplyHeader h{};
  h.schema_version = {kSchemaVersionMajor, kSchemaVersionMinor};
  h.server_instance_id = a.str("robodiffd-7");
  h.client_id = a.str("schema-test-client/" + std::to_string(correlation_id));
  h.correlation_id = correlation_id;
  h.status.code = code;
  h.status.message = a.str(std::move(message));
  return h;
}

robodiff_wire_Reply getFunctionReply(Arena& a) {
  robodiff_wire_Reply r{};
  r.header = replyHeader(a, 7, robodiff_wire_OK, "");
  r.body._d = robodiff_wire_METHOD_GET_FUNCTION;
  auto& g = r.body._u.get_function;
  g.function_id = a.str("fn-5f3a9c");
  g.state = robodiff_wire_FUNCTION_BUILDING;
  auto& ins = a.inputs.emplace_back();
  for (const char* name : {"q", "v", "a"}) {
    robodiff_wire_InputBlock b{};
    b.name = a.str(name);
    b.size = 7;
    ins.push_back(b);
  }
  g.inputs = Arena::seq<dds_sequence_robodiff_wire_InputBlock>(ins);
  auto& outs = a.outputs.emplace_back();
  robodiff_wire_OutputBlock dense{};
  dense.name = a.str("value");
  dense.kind = robodiff_wire_OUTPUT_VALUE;
  dense.rows = 7;
  dense.cols = 1;
  dense.layout = robodiff_wire_LAYOUT_DENSE_ROW_MAJOR;
  dense.nnz = 7;
  outs.push_back(dense);
  robodiff_wire_OutputBlock sparse{};
  sparse.name = a.str("jacobian");
  sparse.kind = robodiff_wire_OUTPUT_JACOBIAN;
  sparse.rows = 3;
  sparse.cols = 4;
  sparse.layout = robodiff_wire_LAYOUT_SPARSE_CSR;
  sparse.nnz = 5;
  auto& rows = a.uints.emplace_back(std::vector<uint32_t>{0, 2, 3, 5});
  auto& cols = a.uints.emplace_back(std::vector<uint32_t>{0, 3, 1, 2, 3});
  sparse.row_offsets = Arena::seq<dds_sequence_unsigned_long>(rows);
  sparse.col_indices = Arena::seq<dds_sequence_unsigned_long>(cols);
  outs.push_back(sparse);
  g.outputs = Arena::seq<dds_sequence_robodiff_wire_OutputBlock>(outs);
  return r;
}

robodiff_wire_Reply evaluateBatchReply(Arena& a) {
  robodiff_wire_Reply r{};
  r.header = replyHeader(a, 42, robodiff_wire_RESOURCE_EXHAUSTED, "batch queue full (64 of 64); retry later");
  r.body._d = robodiff_wire_METHOD_EVALUATE_BATCH;
  auto& e = r.body._u.evaluate_batch;
  e.chunk_index = 1;
  e.chunk_count = 2;
  e.total_knots = kKnots;
  e.first_knot = kKnots / 2;
  e.knot_count = kKnots / 2;
  auto& out = a.doubles.emplace_back(std::size_t{e.knot_count} * kOutputsPerKnot);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = std::cos(0.11 * double(i)) / (1.0 + double(i));
  out[3] = 1e-310;  // subnormal
  e.outputs = Arena::seq<dds_sequence_double>(out);
  return r;
}

// ---- comparing samples (an empty string: equal) --------------------------------------

std::string str(const char* s) { return s ? s : "<null>"; }

#define CMP(field)                                                                             \
  do {                                                                                         \
    if (!(a.field == b.field)) return std::string("field " #field " differs");                \
  } while (0)
#define CMP_STR(field)                                                                         \
  do {                                                                                         \
    if (str(a.field) != str(b.field))                                                          \
      return std::string("field " #field ": '") + str(a.field) + "' != '" + str(b.field) + "'"; \
  } while (0)
#define CMP_SEQ(field)                                                                         \
  do {                                                                                         \
    if (a.field._length != b.field._length) return std::string("length of " #field " differs"); \
    if (a.field._length != 0 &&                                                                \
        std::memcmp(a.field._buffer, b.field._buffer, a.field._length * sizeof(*a.field._buffer)) != 0) \
      return std::string("contents of " #field " differ (bitwise)");                         \
  } while (0)

std::string compare(const robodiff_wire_RequestHeader& a, const robodiff_wire_RequestHeader& b) {
  CMP(schema_version.major);
  CMP(schema_version.minor);
  CMP_STR(client_id);
  CMP(correlation_id);
  CMP(deadline_budget_ns);
  CMP_STR(server_instance_id);
  return {};
}

std::string compare(const robodiff_wire_ReplyHeader& a, const robodiff_wire_ReplyHeader& b) {
  CMP(schema_version.major);
  CMP(schema_version.minor);
  CMP_STR(server_instance_id);
  CMP_STR(client_id);
  CMP(correlation_id);
  CMP(status.code);
  CMP_STR(status.message);
  return {};
}

std::string compare(const robodiff_wire_Request& a, const robodiff_wire_Request& b) {
  if (auto d = compare(a.header, b.header); !d.empty()) return d;
  CMP(body._d);
  switch (a.body._d) {
    case robodiff_wire_METHOD_LOAD_MODEL:
      CMP_STR(body._u.load_model.urdf);
      CMP(body._u.load_model.floating_base);
      CMP_STR(body._u.load_model.options_json);
      return {};
    case robodiff_wire_METHOD_EVALUATE_BATCH:
      CMP_STR(body._u.evaluate_batch.function_id);
      CMP(body._u.evaluate_batch.knot_count);
      CMP_SEQ(body._u.evaluate_batch.inputs);
      return {};
    default:
      return "method not covered by this test";
  }
}

std::string compare(const robodiff_wire_OutputBlock& a, const robodiff_wire_OutputBlock& b) {
  CMP_STR(name);
  CMP(kind);
  CMP(rows);
  CMP(cols);
  CMP(layout);
  CMP(nnz);
  CMP_SEQ(row_offsets);
  CMP_SEQ(col_indices);
  return {};
}

std::string compare(const robodiff_wire_Reply& a, const robodiff_wire_Reply& b) {
  if (auto d = compare(a.header, b.header); !d.empty()) return d;
  CMP(body._d);
  switch (a.body._d) {
    case robodiff_wire_METHOD_GET_FUNCTION: {
      CMP_STR(body._u.get_function.function_id);
      CMP(body._u.get_function.state);
      const auto &ai = a.body._u.get_function.inputs, &bi = b.body._u.get_function.inputs;
      if (ai._length != bi._length) return "input block count differs";
      for (uint32_t i = 0; i < ai._length; ++i)
        if (str(ai._buffer[i].name) != str(bi._buffer[i].name) || ai._buffer[i].size != bi._buffer[i].size)
          return "input block " + std::to_string(i) + " differs";
      const auto &ao = a.body._u.get_function.outputs, &bo = b.body._u.get_function.outputs;
      if (ao._length != bo._length) return "output block count differs";
      for (uint32_t i = 0; i < ao._length; ++i)
        if (auto d = compare(ao._buffer[i], bo._buffer[i]); !d.empty())
          return "output block " + std::to_string(i) + ": " + d;
      return {};
    }
    case robodiff_wire_METHOD_EVALUATE_BATCH:
      CMP(body._u.evaluate_batch.chunk_index);
      CMP(body._u.evaluate_batch.chunk_count);
      CMP(body._u.evaluate_batch.total_knots);
      CMP(body._u.evaluate_batch.first_knot);
      CMP(body._u.evaluate_batch.knot_count);
      CMP_SEQ(body._u.evaluate_batch.outputs);
      return {};
    default:
      return "method not covered by this test";
  }
}

#undef CMP
#undef CMP_STR
#undef CMP_SEQ

// ---- DDS plumbing --------------------------------------------------------------------

struct Endpoints {
  dds_entity_t participant = 0;
  dds_entity_t request_topic = 0, reply_topic = 0;
  dds_entity_t writer = 0, reader = 0;  // the server side: reads requests, writes replies
  std::string error;

  Endpoints(dds_domainid_t domain, const std::string& suffix, bool server) {
    participant = dds_create_participant(domain, nullptr, nullptr);
    if (participant < 0) {
      error = std::string("dds_create_participant: ") + dds_strretcode(participant);
      return;
    }
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(5));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    request_topic = dds_create_topic(participant, &robodiff_wire_Request_desc, ("robodiff_request_" + suffix).c_str(),
                                     qos, nullptr);
    reply_topic = dds_create_topic(participant, &robodiff_wire_Reply_desc, ("robodiff_reply_" + suffix).c_str(),
                                   qos, nullptr);
    if (request_topic < 0 || reply_topic < 0) {
      error = "dds_create_topic failed";
    } else if (server) {
      reader = dds_create_reader(participant, request_topic, qos, nullptr);
      writer = dds_create_writer(participant, reply_topic, qos, nullptr);
    } else {
      reader = dds_create_reader(participant, reply_topic, qos, nullptr);
      writer = dds_create_writer(participant, request_topic, qos, nullptr);
    }
    dds_delete_qos(qos);
    if (error.empty() && (reader < 0 || writer < 0)) error = "dds_create_reader/writer failed";
  }
  ~Endpoints() {
    if (participant > 0) dds_delete(participant);
  }

  // Both the writer and the reader matched by the other side (platform.md: otherwise
  // the first samples are lost).
  bool waitMatched() const {
    const auto end = Clock::now() + kTimeout;
    while (Clock::now() < end) {
      dds_publication_matched_status_t pub{};
      dds_subscription_matched_status_t sub{};
      if (dds_get_publication_matched_status(writer, &pub) == DDS_RETCODE_OK &&
          dds_get_subscription_matched_status(reader, &sub) == DDS_RETCODE_OK && pub.current_count > 0 &&
          sub.current_count > 0)
        return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }

  // Takes up to `count` valid samples, waiting at most kTimeout in all; calls
  // check(sample) for each and returns how many arrived.
  template <class Sample, class Check>
  int take(int count, Check check) const {
    const dds_entity_t waitset = dds_create_waitset(participant);
    const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
    dds_waitset_attach(waitset, condition, 0);
    const auto end = Clock::now() + kTimeout;
    int got = 0;
    while (got < count) {
      const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(end - Clock::now()).count();
      if (left <= 0) break;
      dds_waitset_wait(waitset, nullptr, 0, left);
      void* samples[1] = {nullptr};
      dds_sample_info_t info[1];
      dds_return_t n;
      while ((n = dds_take(reader, samples, info, 1, 1)) > 0) {
        if (info[0].valid_data) {
          check(*static_cast<const Sample*>(samples[0]));
          ++got;
        }
        dds_return_loan(reader, samples, n);
        samples[0] = nullptr;
      }
    }
    dds_delete(waitset);
    dds_delete(condition);
    return got;
  }
};

// The client side, in the child: exit codes say what failed.
int runClient(dds_domainid_t domain, const std::string& suffix) {
  Endpoints ep(domain, suffix, /*server=*/false);
  if (!ep.error.empty()) return 10;
  if (!ep.waitMatched()) return 11;
  Arena a;
  robodiff_wire_Request requests[] = {loadModelRequest(a), evaluateBatchRequest(a)};
  for (auto& r : requests)
    if (dds_write(ep.writer, &r) != DDS_RETCODE_OK) return 12;
  robodiff_wire_Reply expected[] = {getFunctionReply(a), evaluateBatchReply(a)};
  int index = 0, mismatches = 0;
  const int got = ep.take<robodiff_wire_Reply>(2, [&](const robodiff_wire_Reply& r) {
    if (index < 2 && !compare(r, expected[index]).empty()) ++mismatches;
    ++index;
  });
  if (got != 2) return 13;
  if (mismatches) return 14;
  return 0;
}

// The comparison itself must see a difference, or the round trip proves nothing.
TEST(SchemaCompare, SeesOneChangedField) {
  Arena a;
  robodiff_wire_Request x = evaluateBatchRequest(a), y = evaluateBatchRequest(a);
  EXPECT_EQ(compare(x, y), "");
  a.doubles.back()[kKnots * kInputsPerKnot - 1] += 1e-9;
  EXPECT_NE(compare(x, y), "");
  robodiff_wire_Reply r = getFunctionReply(a), t = getFunctionReply(a);
  EXPECT_EQ(compare(r, t), "");
  a.uints.back()[4] = 2;  // the last col_indices of t
  EXPECT_NE(compare(r, t), "");
}

class SchemaDds : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto xml = testing::sourceDir() / "deploy" / "cyclonedds-loopback.xml";
    ASSERT_TRUE(std::filesystem::exists(xml)) << xml;
    setenv("CYCLONEDDS_URI", ("file://" + xml.string()).c_str(), 1);
  }
};

TEST_F(SchemaDds, EnvelopesRoundTripBetweenProcessesOnLoopback) {
  const auto start = Clock::now();
  const auto domain = static_cast<dds_domainid_t>(testing::testDomain());
  const std::string suffix = std::to_string(getpid());
  // Fork before this process touches DDS, so that the child gets a clean runtime.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(runClient(domain, suffix));

  {
    Endpoints ep(domain, suffix, /*server=*/true);
    ASSERT_TRUE(ep.error.empty()) << ep.error;
    EXPECT_TRUE(ep.waitMatched()) << "the child's writer/reader were not matched in time";

    Arena a;
    robodiff_wire_Request expected[] = {loadModelRequest(a), evaluateBatchRequest(a)};
    int index = 0;
    const int got = ep.take<robodiff_wire_Request>(2, [&](const robodiff_wire_Request& r) {
      if (index < 2) {
        EXPECT_EQ(compare(r, expected[index]), "") << "request " << index;
      }
      ++index;
    });
    EXPECT_EQ(got, 2) << "requests received";
    EXPECT_EQ(index, 2);

    robodiff_wire_Reply replies[] = {getFunctionReply(a), evaluateBatchReply(a)};
    for (auto& r : replies) EXPECT_EQ(dds_write(ep.writer, &r), DDS_RETCODE_OK);

    // Keep the writer alive until the child is done (it may need retransmits).
    int status = -1;
    const auto end = Clock::now() + kTimeout + std::chrono::seconds(2);
    pid_t done = 0;
    while ((done = waitpid(child, &status, WNOHANG)) == 0 && Clock::now() < end)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (done == 0) {
      kill(child, SIGKILL);
      waitpid(child, &status, 0);
      FAIL() << "the client process did not finish in time";
    }
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0)
        << "client exit code: 10 setup, 11 not matched, 12 write, 13 replies missing, 14 replies differ";
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  RecordProperty("seconds", std::to_string(seconds));
  EXPECT_LT(seconds, 10.0);
}

}  // namespace
}  // namespace robodiff
