// Requests no DdsConnection would send, written with a raw DDS writer: an unknown method
// discriminator, null strings and sequences, a batch whose knot_count does not match its
// inputs. The server must answer what it can (INVALID_ARGUMENT / NOT_FOUND), never crash,
// and keep serving.

#include <gtest/gtest.h>

#include <map>
#include <thread>

#include "dds_test_env.hpp"
#include "fake_service.hpp"
#include "robodiff/schema/dds_codec.hpp"
#include "robodiff/schema/dds_topics.hpp"
#include "robodiff/server/dds_server.hpp"

namespace robodiff {
namespace {

using namespace std::chrono_literals;
using dds_codec::DdsEndpoints;

void setHeader(robodiff_wire_Request& r, std::uint64_t correlation_id) {
  dds_codec::toWire(rpc::RequestHeader{{}, "raw-client", correlation_id, 0, ""}, r.header);
}

class DdsMalformed : public testing::DdsTest {};

TEST_F(DdsMalformed, RequestsAreAnsweredOrDroppedNeverFatal) {
  const std::uint32_t domain = testing::testDomain();
  testing::FakeService service("srv-raw");
  server::Logger log(stderr, server::LogLevel::Error);
  server::DdsServerOptions options;
  options.domain_id = domain;
  server::DdsServer server(service, options, log);
  server.start();

  DdsEndpoints raw(domain, dds_codec::kDefaultServiceName, DdsEndpoints::Side::Client);
  ASSERT_TRUE(testing::eventually(
      [&] {
        dds_publication_matched_status_t pub{};
        dds_subscription_matched_status_t sub{};
        dds_get_publication_matched_status(raw.writer(), &pub);
        dds_get_subscription_matched_status(raw.reader(), &sub);
        return pub.current_count > 0 && sub.current_count > 0;
      },
      10s));
  std::this_thread::sleep_for(50ms);

  {  // 1: a method this server does not know (DDS may refuse to write it at all)
    dds_codec::WireRequest r;
    setHeader(r.get(), 1);
    r->body._d = static_cast<robodiff_wire_Method>(42);
    (void)dds_write(raw.writer(), &r.get());
  }
  {  // 2: Evaluate with a null function id and no inputs
    dds_codec::WireRequest r;
    setHeader(r.get(), 2);
    r->body._d = robodiff_wire_METHOD_EVALUATE;
    ASSERT_EQ(dds_write(raw.writer(), &r.get()), DDS_RETCODE_OK);
  }
  {  // 3: EvaluateBatch claiming 1000000 knots with 3 doubles
    dds_codec::WireRequest r;
    setHeader(r.get(), 3);
    r->body._d = robodiff_wire_METHOD_EVALUATE_BATCH;
    r->body._u.evaluate_batch.function_id = dds_codec::dupString("fn-double");
    r->body._u.evaluate_batch.knot_count = 1000000;
    dds_codec::allocDoubles(r->body._u.evaluate_batch.inputs, 3);
    for (double& x : dds_codec::view(r->body._u.evaluate_batch.inputs)) x = 1;
    ASSERT_EQ(dds_write(raw.writer(), &r.get()), DDS_RETCODE_OK);
  }
  {  // 4: a plain Health: the server is still there
    dds_codec::WireRequest r;
    setHeader(r.get(), 4);
    r->body._d = robodiff_wire_METHOD_HEALTH;
    ASSERT_EQ(dds_write(raw.writer(), &r.get()), DDS_RETCODE_OK);
  }

  std::map<std::uint64_t, StatusCode> codes;
  const dds_entity_t waitset = dds_create_waitset(raw.participant());
  const dds_entity_t readable = dds_create_readcondition(raw.reader(), DDS_ANY_STATE);
  dds_waitset_attach(waitset, readable, 0);
  const auto end = std::chrono::steady_clock::now() + 10s;
  // Replies to posted requests (3 and 4) may come in either order.
  auto answered = [&] { return codes.count(2) && codes.count(3) && codes.count(4); };
  while (!answered() && std::chrono::steady_clock::now() < end) {
    dds_waitset_wait(waitset, nullptr, 0, DDS_MSECS(100));
    void* samples[1] = {nullptr};
    dds_sample_info_t info[1];
    while (dds_take(raw.reader(), samples, info, 1, 1) > 0) {
      if (info[0].valid_data) {
        const auto& reply = *static_cast<const robodiff_wire_Reply*>(samples[0]);
        codes[reply.header.correlation_id] = dds_codec::statusFromWire(reply.header.status.code);
      }
      dds_return_loan(raw.reader(), samples, 1);
      samples[0] = nullptr;
    }
  }
  dds_delete(readable);
  dds_delete(waitset);

  ASSERT_TRUE(codes.count(4)) << "the server stopped answering";
  EXPECT_EQ(codes[4], StatusCode::Ok);
  if (codes.count(1)) {  // DDS may drop a sample with an enum value out of range, on either side
    EXPECT_EQ(codes[1], StatusCode::InvalidArgument);
  }
  std::fprintf(stderr, "unknown method answered: %s\n", codes.count(1) ? "yes" : "no (dropped by DDS)");
  ASSERT_TRUE(codes.count(2));
  EXPECT_EQ(codes[2], StatusCode::NotFound);  // "" is no function
  ASSERT_TRUE(codes.count(3));
  EXPECT_EQ(codes[3], StatusCode::InvalidArgument);
}

}  // namespace
}  // namespace robodiff
