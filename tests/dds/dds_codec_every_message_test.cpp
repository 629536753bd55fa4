// Every message of ROBODIFF_RPC_MESSAGES through the DDS codec, with random contents drawn
// through its field list, inside the envelope and owning sample the transport uses; and
// schema/robodiff.idl checked against the field lists, struct by struct, so that the IDL
// and messages.hpp cannot drift apart.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "robodiff/schema/dds_codec.hpp"
#include "support/message_samples.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using namespace dds_codec;
using testing::fieldNames;
using testing::firstDifference;
using testing::fillRandom;
using testing::forEachMessage;
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
  EXPECT_EQ(kinds, 22);
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

// struct name -> its field names in order, from the IDL text.
std::map<std::string, std::vector<std::string>> idlStructs(const std::string& idl) {
  std::map<std::string, std::vector<std::string>> structs;
  const std::regex struct_re(R"(struct\s+(\w+)\s*\{([^}]*)\})");
  const std::regex field_re(R"((\w+)\s*;)");
  for (auto it = std::sregex_iterator(idl.begin(), idl.end(), struct_re); it != std::sregex_iterator(); ++it) {
    std::string body = (*it)[2];
    body = std::regex_replace(body, std::regex(R"(//[^\n]*)"), "");
    auto& fields = structs[(*it)[1]];
    for (auto f = std::sregex_iterator(body.begin(), body.end(), field_re); f != std::sregex_iterator(); ++f)
      fields.push_back((*f)[1]);
  }
  return structs;
}

template <class T>
void expectIdlAgrees(const std::map<std::string, std::vector<std::string>>& idl, std::set<std::string>& seen) {
  const std::string name = rpc::Fields<T>::kName;
  seen.insert(name);
  const auto it = idl.find(name);
  ASSERT_NE(it, idl.end()) << name << " has a field list but no struct in robodiff.idl";
  EXPECT_EQ(it->second, fieldNames<T>()) << name << ": robodiff.idl and messages.hpp list different fields";
}

TEST(DdsCodecEveryMessage, TheIdlHasTheFieldListsStructs) {
  const auto idl = idlStructs(testing::readFile(testing::sourceDir() / "schema/robodiff.idl"));
  ASSERT_GT(idl.size(), 30u);
  std::set<std::string> seen;
  forEachMessage([&](auto empty) { expectIdlAgrees<decltype(empty)>(idl, seen); });
  expectIdlAgrees<Status>(idl, seen);
  expectIdlAgrees<rpc::SchemaVersion>(idl, seen);
  expectIdlAgrees<rpc::RequestHeader>(idl, seen);
  expectIdlAgrees<rpc::ReplyHeader>(idl, seen);
  expectIdlAgrees<rpc::InputBlock>(idl, seen);
  expectIdlAgrees<rpc::OutputBlock>(idl, seen);
  expectIdlAgrees<rpc::FunctionSummary>(idl, seen);
  expectIdlAgrees<rpc::JobInfo>(idl, seen);
  expectIdlAgrees<rpc::MethodStats>(idl, seen);
  expectIdlAgrees<rpc::StatusCount>(idl, seen);
  expectIdlAgrees<rpc::TransportCounts>(idl, seen);
  // The envelopes are the only IDL structs without a C++ counterpart.
  for (const auto& [name, fields] : idl) {
    if (name != "Request" && name != "Reply") EXPECT_TRUE(seen.count(name)) << name << " is in robodiff.idl only";
  }
}

// The checker itself notices a drift.
TEST(DdsCodecEveryMessage, TheIdlCheckSeesAMissingField) {
  const auto idl = idlStructs("@final struct ReleaseReply {\n  unsigned long references;  // renamed\n};\n");
  EXPECT_NE(idl.at("ReleaseReply"), fieldNames<rpc::ReleaseReply>());
  EXPECT_EQ(idlStructs("struct ReleaseReply { unsigned long references_left; };").at("ReleaseReply"),
            fieldNames<rpc::ReleaseReply>());
}

}  // namespace
}  // namespace robodiff
