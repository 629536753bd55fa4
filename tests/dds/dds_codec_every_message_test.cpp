// Every message of ROBODIFF_RPC_MESSAGES through the DDS codec, with random contents drawn
// through its field list, inside the envelope and owning sample the transport uses. The
// idlc C types come from the IDL the build writes from the same field lists
// (tests/schema/idl_writer_test.cpp), so a field added to messages.hpp is covered here
// with no change.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <variant>

#include "robodiff/schema/dds_codec.hpp"
#include "support/message_samples.hpp"

namespace robodiff {
namespace {

using namespace dds_codec;
using testing::firstDifference;
using testing::fillRandom;
using testing::forEachRandomMessage;

template <class M, class Variant>
struct IsAlternative;
template <class M, class... Ts>
struct IsAlternative<M, std::variant<Ts...>> : std::bool_constant<(std::is_same_v<M, Ts> || ...)> {};

// The message inside a request or reply body, to the wire sample and back.
template <class M>
M throughEnvelope(const M& in) {
  if constexpr (IsAlternative<M, RequestBody>::value) {
    WireRequest sample;
    toWire(RequestBody(in), sample->body);
    RequestBody out;
    EXPECT_TRUE(fromWire(sample->body, out).ok());
    return std::get<M>(out);
  } else {
    WireReply sample;
    toWire(ReplyBody(in), sample->body);
    ReplyBody out;
    EXPECT_TRUE(fromWire(sample->body, out).ok());
    return std::get<M>(out);
  }
}

TEST(DdsCodecEveryMessage, RandomMessagesRoundTripFieldForField) {
  const int kinds = forEachRandomMessage(20261126, 50, [](const auto& in, int sample) {
    EXPECT_EQ(firstDifference(in, throughEnvelope(in)), "")
        << rpc::Fields<std::remove_cvref_t<decltype(in)>>::kName << " sample " << sample;
  });
  EXPECT_EQ(kinds, 28);
}

TEST(DdsCodecEveryMessage, HeadersRoundTripFieldForField) {
  std::mt19937_64 rng(3);
  for (int sample = 0; sample < 50; ++sample) {
    rpc::RequestHeader request;
    fillRandom(request, rng);
    WireRequest r;
    toWire(request, r->header);
    EXPECT_EQ(firstDifference(request, fromWire(r->header)), "");
    rpc::ReplyHeader reply;
    fillRandom(reply, rng);
    WireReply p;
    toWire(reply, p->header);
    EXPECT_EQ(firstDifference(reply, fromWire(p->header)), "");
  }
}

}  // namespace
}  // namespace robodiff
