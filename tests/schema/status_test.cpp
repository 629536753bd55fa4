#include <gtest/gtest.h>

#include "robodiff.h"  // idlc's C types of build/schema/robodiff.idl
#include "robodiff/schema/status.hpp"

namespace robodiff {
namespace {

TEST(SchemaStatus, NamesRoundTrip) {
  for (std::uint32_t v = 0; v < kStatusCodeCount; ++v) {
    const auto code = statusCodeFromValue(v);
    ASSERT_TRUE(code);
    const std::string name = toString(*code);
    const auto parsed = parseStatusCode(name);
    ASSERT_TRUE(parsed) << name;
    EXPECT_EQ(*parsed, *code) << name;
  }
  EXPECT_EQ(toString(StatusCode::Ok), "OK");
  EXPECT_EQ(toString(StatusCode::InvalidArgument), "INVALID_ARGUMENT");
  EXPECT_EQ(toString(StatusCode::ResourceExhausted), "RESOURCE_EXHAUSTED");
  EXPECT_EQ(toString(StatusCode::Unavailable), "UNAVAILABLE");
  EXPECT_EQ(toString(static_cast<StatusCode>(99)), "STATUS_CODE(99)");
  EXPECT_FALSE(parseStatusCode("ok"));
  EXPECT_FALSE(parseStatusCode("NOT_A_CODE"));
  EXPECT_FALSE(parseStatusCode(""));
  EXPECT_FALSE(statusCodeFromValue(kStatusCodeCount));
}

TEST(SchemaStatus, ValuesEqualTheIdlEnumAndGrpc) {
  // The generated C enumerators, with gRPC's numbers.
  const std::pair<StatusCode, int> pairs[] = {
      {StatusCode::Ok, robodiff_wire_OK},
      {StatusCode::Cancelled, robodiff_wire_CANCELLED},
      {StatusCode::Unknown, robodiff_wire_UNKNOWN},
      {StatusCode::InvalidArgument, robodiff_wire_INVALID_ARGUMENT},
      {StatusCode::DeadlineExceeded, robodiff_wire_DEADLINE_EXCEEDED},
      {StatusCode::NotFound, robodiff_wire_NOT_FOUND},
      {StatusCode::AlreadyExists, robodiff_wire_ALREADY_EXISTS},
      {StatusCode::PermissionDenied, robodiff_wire_PERMISSION_DENIED},
      {StatusCode::ResourceExhausted, robodiff_wire_RESOURCE_EXHAUSTED},
      {StatusCode::FailedPrecondition, robodiff_wire_FAILED_PRECONDITION},
      {StatusCode::Aborted, robodiff_wire_ABORTED},
      {StatusCode::OutOfRange, robodiff_wire_OUT_OF_RANGE},
      {StatusCode::Unimplemented, robodiff_wire_UNIMPLEMENTED},
      {StatusCode::Internal, robodiff_wire_INTERNAL},
      {StatusCode::Unavailable, robodiff_wire_UNAVAILABLE},
      {StatusCode::DataLoss, robodiff_wire_DATA_LOSS},
      {StatusCode::Unauthenticated, robodiff_wire_UNAUTHENTICATED},
  };
  ASSERT_EQ(std::size(pairs), kStatusCodeCount);
  for (const auto& [cpp, idl] : pairs) EXPECT_EQ(static_cast<int>(cpp), idl) << toString(cpp);
  EXPECT_EQ(static_cast<int>(StatusCode::InvalidArgument), 3);  // gRPC's numbers
  EXPECT_EQ(static_cast<int>(StatusCode::Unavailable), 14);
  EXPECT_EQ(kSchemaVersionMajor, robodiff_wire_SCHEMA_VERSION_MAJOR);
  EXPECT_EQ(kSchemaVersionMinor, robodiff_wire_SCHEMA_VERSION_MINOR);
}

TEST(SchemaStatus, CompatibilityRule) {
  // Same major, client minor <= server minor.
  EXPECT_TRUE(compatible(kSchemaVersionMajor, kSchemaVersionMinor));
  EXPECT_TRUE(compatible(1, 0, 1, 3));
  EXPECT_TRUE(compatible(1, 3, 1, 3));
  EXPECT_FALSE(compatible(1, 4, 1, 3));  // client newer than server
  EXPECT_FALSE(compatible(2, 0, 1, 3));
  EXPECT_FALSE(compatible(0, 9, 1, 3));

  EXPECT_TRUE(checkSchemaVersion(1, 2, 1, 3).ok());
  const Status newer = checkSchemaVersion(1, 4, 1, 3);
  EXPECT_EQ(newer.code, StatusCode::FailedPrecondition);
  EXPECT_NE(newer.message.find("1.4"), std::string::npos) << newer.message;
  EXPECT_NE(newer.message.find("1.3"), std::string::npos) << newer.message;
  EXPECT_NE(newer.message.find("upgrade robodiffd"), std::string::npos) << newer.message;
  const Status major = checkSchemaVersion(2, 0, 1, 3);
  EXPECT_EQ(major.code, StatusCode::FailedPrecondition);
  EXPECT_NE(major.message.find("major"), std::string::npos) << major.message;
}

}  // namespace
}  // namespace robodiff
