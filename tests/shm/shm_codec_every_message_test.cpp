// Every message of ROBODIFF_RPC_MESSAGES through the iceoryx codec, with random contents
// drawn through its field list: it round trips field for field, and every cut-off or
// overlong body is INVALID_ARGUMENT naming the message, never a crash or a wrong value.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <type_traits>

#include "robodiff/schema/shm_codec.hpp"
#include "support/message_samples.hpp"

namespace robodiff::shm {
namespace {

using testing::firstDifference;
using testing::fillRandom;
using testing::forEachMessage;
using testing::forEachRandomMessage;

template <class M>
constexpr bool kEvaluateLayout =
    std::is_same_v<M, rpc::EvaluateRequest> || std::is_same_v<M, rpc::EvaluateBatchRequest> ||
    std::is_same_v<M, rpc::EvaluateReply> || std::is_same_v<M, rpc::EvaluateBatchReply>;

TEST(ShmCodecEveryMessage, RandomMessagesRoundTripFieldForField) {
  const int kinds = forEachRandomMessage(20261126, 50, [](const auto& in, int sample) {
    using M = std::remove_cvref_t<decltype(in)>;
    const auto bytes = encode(in);
    M out;
    const Status status = decode(bytes, out);
    ASSERT_TRUE(status.ok()) << rpc::Fields<M>::kName << ": " << status.message;
    EXPECT_EQ(firstDifference(in, out), "") << rpc::Fields<M>::kName << " sample " << sample;
  });
  EXPECT_EQ(kinds, 28);
}

TEST(ShmCodecEveryMessage, EveryCutAndAnyTrailingByteIsInvalid) {
  std::mt19937_64 rng(7);
  forEachMessage([&](auto empty) {
    using M = decltype(empty);
    for (int sample = 0; sample < 5; ++sample) {
      M in;
      fillRandom(in, rng);
      const auto bytes = encode(in);
      for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
        M partial;
        const Status status = decode(std::span(bytes.data(), cut), partial);
        ASSERT_EQ(status.code, StatusCode::InvalidArgument) << rpc::Fields<M>::kName << " cut at " << cut;
        if constexpr (!kEvaluateLayout<M>) {
          EXPECT_NE(status.message.find(rpc::Fields<M>::kName), std::string::npos) << status.message;
        }
      }
      auto longer = bytes;
      longer.push_back(std::byte{1});
      M extra;
      EXPECT_EQ(decode(longer, extra).code, StatusCode::InvalidArgument) << rpc::Fields<M>::kName;
    }
  });
}

// A sequence whose count claims more elements than the body could hold is refused before
// anything is allocated, naming the field.
TEST(ShmCodecEveryMessage, HugeCountsAreRefusedWithTheFieldsName) {
  rpc::ListFunctionsReply list;
  auto bytes = encode(list);
  const std::uint32_t huge = 0xFFFFFFF0u;
  std::memcpy(bytes.data(), &huge, sizeof huge);  // functions' count comes first
  rpc::ListFunctionsReply out;
  const Status status = decode(bytes, out);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("functions claims 4294967280 elements"), std::string::npos) << status.message;
}

}  // namespace
}  // namespace robodiff::shm
