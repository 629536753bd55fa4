// The IDL writer (robodiff/schema/idl_writer.hpp), from which the build makes robodiff.idl's
// structs out of messages.hpp's field lists: every wire struct is written with every field
// under its IDL type and after the structs it contains, a field the wire cannot carry is
// reported by name, and the frame (schema/robodiff.idl.in) takes the structs at its one
// marker and has every enum the messages use, with as many values as the C++ enum.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "robodiff/schema/idl_writer.hpp"
#include "support/message_samples.hpp"
#include "support/test_paths.hpp"

namespace robodiff::rpc {

// Test-only structs: one with a field of every other mapped kind, one with fields the wire
// cannot carry.
struct IdlProbe {
  std::int32_t small = 0;
  std::int64_t big = 0;
  float ratio = 0;
  std::vector<std::vector<double>> rows;
  std::vector<InputBlock> blocks;
  JobState state = JobState::Queued;
  StatusCode code = StatusCode::Ok;
};
ROBODIFF_FIELDS(IdlProbe, small, big, ratio, rows, blocks, state, code);

struct IdlProbeUnmapped {
  std::string name;
  std::int8_t tiny = 0;
  std::vector<char> letters;
};
ROBODIFF_FIELDS(IdlProbeUnmapped, name, tiny, letters);

}  // namespace robodiff::rpc

namespace robodiff {
namespace {

enum class EnumWithoutIdlName { A, B };

using Field = std::pair<std::string, std::string>;  // IDL type, name

// struct name -> its fields, and the structs in the order written, from the writer's text.
struct ParsedStructs {
  std::map<std::string, std::vector<Field>> fields;
  std::vector<std::string> order;
};

ParsedStructs parseStructs(const std::string& idl) {
  ParsedStructs parsed;
  const std::regex struct_re(R"(@final struct (\w+) \{\n((?:    [^\n]*\n)*)  \};)");
  const std::regex field_re(R"(    (.+) (\w+);\n)");
  for (auto it = std::sregex_iterator(idl.begin(), idl.end(), struct_re); it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[1], body = (*it)[2];
    parsed.order.push_back(name);
    auto& fields = parsed.fields[name];
    for (auto f = std::sregex_iterator(body.begin(), body.end(), field_re); f != std::sregex_iterator(); ++f)
      fields.emplace_back((*f)[1], (*f)[2]);
  }
  return parsed;
}

// Calls f(T{}) for every struct the wire carries: the messages and what they contain.
template <class F>
void forEachWireStruct(F&& f) {
  testing::forEachMessage(f);
  f(Status{});
  f(rpc::SchemaVersion{});
  f(rpc::RequestHeader{});
  f(rpc::ReplyHeader{});
  f(rpc::InputBlock{});
  f(rpc::OutputBlock{});
  f(rpc::FunctionSummary{});
  f(rpc::JobInfo{});
  f(rpc::MethodStats{});
  f(rpc::StatusCount{});
  f(rpc::TransportCounts{});
  f(rpc::FleetPeer{});
  f(rpc::FleetFigures{});
}

TEST(IdlWriter, MapsEachCppTypeToItsIdlType) {
  EXPECT_EQ(idl::IdlType<std::string>::name(), "string");
  EXPECT_EQ(idl::IdlType<bool>::name(), "boolean");
  EXPECT_EQ(idl::IdlType<double>::name(), "double");
  EXPECT_EQ(idl::IdlType<float>::name(), "float");
  EXPECT_EQ(idl::IdlType<std::uint8_t>::name(), "octet");
  EXPECT_EQ(idl::IdlType<std::vector<std::uint8_t>>::name(), "sequence<octet>");
  EXPECT_EQ(idl::IdlType<std::uint16_t>::name(), "unsigned short");
  EXPECT_EQ(idl::IdlType<std::uint32_t>::name(), "unsigned long");
  EXPECT_EQ(idl::IdlType<std::uint64_t>::name(), "unsigned long long");
  EXPECT_EQ(idl::IdlType<std::int32_t>::name(), "long");
  EXPECT_EQ(idl::IdlType<std::int64_t>::name(), "long long");
  EXPECT_EQ(idl::IdlType<std::vector<std::string>>::name(), "sequence<string>");
  EXPECT_EQ(idl::IdlType<rpc::JobInfo>::name(), "JobInfo");
  EXPECT_EQ(idl::IdlType<std::vector<rpc::OutputBlock>>::name(), "sequence<OutputBlock>");
  EXPECT_EQ(idl::IdlType<StatusCode>::name(), "StatusCode");
  EXPECT_EQ(idl::IdlType<rpc::Method>::name(), "Method");
  EXPECT_EQ(idl::IdlType<rpc::OutputLayout>::name(), "OutputLayout");

  idl::IdlWriter writer;
  writer.add<rpc::IdlProbe>();
  EXPECT_TRUE(writer.errors().empty());
  EXPECT_EQ(writer.order(), (std::vector<std::string>{"InputBlock", "IdlProbe"}));
  EXPECT_NE(writer.text().find("  @final struct IdlProbe {\n"
                               "    long small;\n"
                               "    long long big;\n"
                               "    float ratio;\n"
                               "    sequence<sequence<double>> rows;\n"
                               "    sequence<InputBlock> blocks;\n"
                               "    JobState state;\n"
                               "    StatusCode code;\n"
                               "  };\n"),
            std::string::npos)
      << writer.text();
}

// The wire carries none of these: a field of such a type is reported, naming the field.
static_assert(!idl::Mappable<std::int8_t>);
static_assert(!idl::Mappable<char>);
static_assert(!idl::Mappable<std::vector<char>>);
static_assert(!idl::Mappable<std::map<std::string, double>>);
static_assert(!idl::Mappable<EnumWithoutIdlName>);
static_assert(!idl::Mappable<ParsedStructs>);  // no field list
static_assert(idl::Mappable<std::vector<std::vector<rpc::JobInfo>>>);

TEST(IdlWriter, ReportsEachFieldWithNoIdlTypeByName) {
  idl::IdlWriter writer;
  writer.add<rpc::IdlProbeUnmapped>();
  ASSERT_EQ(writer.errors().size(), 2u) << writer.text();
  const std::string& first = writer.errors()[0];
  EXPECT_EQ(first.rfind("IdlProbeUnmapped.tiny: its C++ type has no IDL type", 0), 0u) << first;
  EXPECT_NE(writer.errors()[0].find("idl_writer.hpp"), std::string::npos) << writer.errors()[0];
  EXPECT_EQ(writer.errors()[1].rfind("IdlProbeUnmapped.letters:", 0), 0u) << writer.errors()[1];
}

TEST(IdlWriter, WritesEveryWireStructWithItsFieldsInOrder) {
  const idl::IdlWriter writer = idl::writeWireStructs();
  ASSERT_TRUE(writer.errors().empty()) << writer.errors().front();
  const ParsedStructs idl = parseStructs(writer.text());
  EXPECT_EQ(idl.order, writer.order());
  std::set<std::string> listed;
  forEachWireStruct([&](auto empty) {
    using T = decltype(empty);
    const std::string name = rpc::Fields<T>::kName;
    listed.insert(name);
    ASSERT_TRUE(idl.fields.count(name)) << name << " is not written";
    std::vector<std::string> names;
    for (const auto& [type, field] : idl.fields.at(name)) names.push_back(field);
    EXPECT_EQ(names, testing::fieldNames<T>()) << name;
  });
  EXPECT_EQ(listed.size(), 41u);
  EXPECT_EQ(idl.fields.size(), listed.size()) << "a written struct is not one the wire carries";
  EXPECT_EQ(std::set<std::string>(idl.order.begin(), idl.order.end()).size(), idl.order.size()) << "one struct twice";

  // The types as the hand-written IDL had them (the wire is unchanged).
  const std::vector<std::pair<std::string, Field>> expected = {
      {"SchemaVersion", {"unsigned short", "major"}},       {"Status", {"StatusCode", "code"}},
      {"RequestHeader", {"unsigned long long", "correlation_id"}},
      {"LoadModelRequest", {"boolean", "floating_base"}},  {"LoadModelReply", {"sequence<string>", "joint_names"}},
      {"LoadModelReply", {"unsigned long", "nv"}},          {"OutputBlock", {"OutputKind", "kind"}},
      {"OutputBlock", {"sequence<unsigned long>", "row_offsets"}},
      {"GetFunctionReply", {"sequence<InputBlock>", "inputs"}},
      {"EvaluateRequest", {"sequence<double>", "inputs"}}, {"JobInfo", {"double", "progress"}},
      {"JobResultReply", {"JobInfo", "info"}},             {"MethodStats", {"Method", "method"}},
      {"HealthReply", {"ServingState", "state"}},          {"HealthReply", {"sequence<TransportCounts>", "transports"}},
      {"QueryArtifactReply", {"ArtifactState", "state"}},  {"FetchArtifactChunkReply", {"sequence<octet>", "data"}},
      {"FleetFigures", {"sequence<FleetPeer>", "peers"}},  {"FleetStatusReply", {"FleetFigures", "fleet"}},
  };
  for (const auto& [name, field] : expected) {
    const auto& fields = idl.fields.at(name);
    EXPECT_NE(std::find(fields.begin(), fields.end(), field), fields.end()) << name << "." << field.second;
  }
}

// The IDL type a field names, without its sequence<...>.
std::string elementType(std::string type) {
  while (type.rfind("sequence<", 0) == 0) type = type.substr(9, type.size() - 10);
  return type;
}

TEST(IdlWriter, WritesEachStructAfterTheStructsItContains) {
  const ParsedStructs idl = parseStructs(idl::writeWireStructs().text());
  std::map<std::string, std::size_t> position;
  for (std::size_t i = 0; i < idl.order.size(); ++i) position[idl.order[i]] = i;
  int contained = 0;
  for (const auto& [name, fields] : idl.fields) {
    for (const auto& [type, field] : fields) {
      const auto it = position.find(elementType(type));
      if (it == position.end()) continue;
      ++contained;
      EXPECT_LT(it->second, position.at(name)) << name << "." << field << " names " << type << ", written later";
    }
  }
  // schema_version (twice), status, inputs, outputs, functions, jobs, info, methods, errors, transports,
  // peers, fleet
  EXPECT_EQ(contained, 13);
}

TEST(IdlWriter, PutsTheVersionAndTheStructsAtTheFramesOneMarker) {
  const std::string frame = testing::readFile(testing::sourceDir() / "schema/robodiff.idl.in");
  const idl::FilledFrame filled = idl::writeWireIdl(frame);
  ASSERT_EQ(filled.error, "");
  EXPECT_EQ(filled.idl.find(idl::kStructsMarker), std::string::npos);
  const std::size_t enums_end = filled.idl.find("enum ServingState");
  const std::size_t version = filled.idl.find("const unsigned short SCHEMA_VERSION_MAJOR = " +
                                              std::to_string(kSchemaVersionMajor) + ";\n");
  const std::size_t first_struct = filled.idl.find("@final struct SchemaVersion {");
  const std::size_t unions = filled.idl.find("@final union RequestBody");
  EXPECT_LT(enums_end, version);
  const std::string minor = "const unsigned short SCHEMA_VERSION_MINOR = " + std::to_string(kSchemaVersionMinor);
  EXPECT_NE(filled.idl.find(minor + ";\n"), std::string::npos);
  EXPECT_LT(version, first_struct);
  EXPECT_LT(first_struct, unions);
  EXPECT_LT(unions, filled.idl.find("@final struct Request {"));
  EXPECT_EQ(filled.idl.rfind("// Generated at build time", 0), 0u);
  EXPECT_NE(filled.idl.find(idl::writeWireStructs().text()), std::string::npos);

  const auto none = idl::fillFrame("module m {\n};\n", "struct S {};\n");
  EXPECT_NE(none.error.find("exactly one line \"// @WIRE_VERSION_AND_STRUCTS@\""), std::string::npos) << none.error;
  EXPECT_NE(none.error.find("it has 0"), std::string::npos) << none.error;
  const auto twice = idl::fillFrame("  // @WIRE_VERSION_AND_STRUCTS@\n// @WIRE_VERSION_AND_STRUCTS@\n", "");
  EXPECT_NE(twice.error.find("it has 2"), std::string::npos) << twice.error;
  const auto small = idl::fillFrame("a\n  // @WIRE_VERSION_AND_STRUCTS@\nb\n", "S\n");
  EXPECT_EQ(small.error, "");
  EXPECT_NE(small.idl.find("\na\n"), std::string::npos) << small.idl;
  EXPECT_EQ(small.idl.substr(small.idl.size() - 4), "S\nb\n") << small.idl;
}

// enum name -> its values, from the frame.
std::map<std::string, int> frameEnums(const std::string& frame) {
  std::map<std::string, int> enums;
  const std::regex enum_re(R"(enum (\w+) \{([^}]*)\})");
  for (auto it = std::sregex_iterator(frame.begin(), frame.end(), enum_re); it != std::sregex_iterator(); ++it) {
    const std::string body = std::regex_replace(std::string((*it)[2]), std::regex(R"(//[^\n]*)"), "");
    const std::regex value_re(R"(\b[A-Z][A-Z0-9_]*\b)");
    enums[(*it)[1]] = static_cast<int>(std::distance(std::sregex_iterator(body.begin(), body.end(), value_re),
                                                     std::sregex_iterator()));
  }
  return enums;
}

template <class E>
void expectFrameEnum(const std::map<std::string, int>& enums) {
  const std::string name = rpc::idlName(E{});
  ASSERT_TRUE(enums.count(name)) << name << " is not an enum of robodiff.idl.in";
  EXPECT_EQ(enums.at(name), static_cast<int>(rpc::valueCount(E{}))) << name;
}

TEST(IdlWriter, TheFrameHasEveryEnumWithItsValueCount) {
  const auto enums = frameEnums(testing::readFile(testing::sourceDir() / "schema/robodiff.idl.in"));
  EXPECT_EQ(enums.size(), 8u);
  expectFrameEnum<StatusCode>(enums);
  expectFrameEnum<rpc::Method>(enums);
  expectFrameEnum<rpc::FunctionState>(enums);
  expectFrameEnum<rpc::OutputKind>(enums);
  expectFrameEnum<rpc::OutputLayout>(enums);
  expectFrameEnum<rpc::JobState>(enums);
  expectFrameEnum<rpc::ServingState>(enums);
  expectFrameEnum<rpc::ArtifactState>(enums);
}

}  // namespace
}  // namespace robodiff
