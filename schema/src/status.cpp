#include "robodiff/schema/status.hpp"

#include <array>

#include "robodiff.h"  // idlc's C types of build/schema/robodiff.idl (robodiff.idl.in + messages.hpp)

namespace robodiff {

// The C++ mirror must keep the IDL's numbers.
#define ROBODIFF_CHECK_CODE(cpp, idl) \
  static_assert(static_cast<std::uint32_t>(StatusCode::cpp) == static_cast<std::uint32_t>(robodiff_wire_##idl), \
                "StatusCode::" #cpp " differs from the IDL's " #idl)
ROBODIFF_CHECK_CODE(Ok, OK);
ROBODIFF_CHECK_CODE(Cancelled, CANCELLED);
ROBODIFF_CHECK_CODE(Unknown, UNKNOWN);
ROBODIFF_CHECK_CODE(InvalidArgument, INVALID_ARGUMENT);
ROBODIFF_CHECK_CODE(DeadlineExceeded, DEADLINE_EXCEEDED);
ROBODIFF_CHECK_CODE(NotFound, NOT_FOUND);
ROBODIFF_CHECK_CODE(AlreadyExists, ALREADY_EXISTS);
ROBODIFF_CHECK_CODE(PermissionDenied, PERMISSION_DENIED);
ROBODIFF_CHECK_CODE(ResourceExhausted, RESOURCE_EXHAUSTED);
ROBODIFF_CHECK_CODE(FailedPrecondition, FAILED_PRECONDITION);
ROBODIFF_CHECK_CODE(Aborted, ABORTED);
ROBODIFF_CHECK_CODE(OutOfRange, OUT_OF_RANGE);
ROBODIFF_CHECK_CODE(Unimplemented, UNIMPLEMENTED);
ROBODIFF_CHECK_CODE(Internal, INTERNAL);
ROBODIFF_CHECK_CODE(Unavailable, UNAVAILABLE);
ROBODIFF_CHECK_CODE(DataLoss, DATA_LOSS);
ROBODIFF_CHECK_CODE(Unauthenticated, UNAUTHENTICATED);
#undef ROBODIFF_CHECK_CODE
static_assert(kSchemaVersionMajor == robodiff_wire_SCHEMA_VERSION_MAJOR, "schema major differs from the IDL");
static_assert(kSchemaVersionMinor == robodiff_wire_SCHEMA_VERSION_MINOR, "schema minor differs from the IDL");

namespace {
constexpr std::array<std::string_view, kStatusCodeCount> kNames = {
    "OK",                 "CANCELLED",        "UNKNOWN",       "INVALID_ARGUMENT", "DEADLINE_EXCEEDED",
    "NOT_FOUND",          "ALREADY_EXISTS",   "PERMISSION_DENIED", "RESOURCE_EXHAUSTED",
    "FAILED_PRECONDITION", "ABORTED",         "OUT_OF_RANGE",  "UNIMPLEMENTED",    "INTERNAL",
    "UNAVAILABLE",        "DATA_LOSS",        "UNAUTHENTICATED"};

std::string versionString(std::uint16_t major, std::uint16_t minor) {
  return std::to_string(major) + "." + std::to_string(minor);
}
}  // namespace

std::string toString(StatusCode code) {
  const auto value = static_cast<std::uint32_t>(code);
  if (value < kStatusCodeCount) return std::string(kNames[value]);
  return "STATUS_CODE(" + std::to_string(value) + ")";
}

std::optional<StatusCode> parseStatusCode(std::string_view name) {
  for (std::uint32_t i = 0; i < kStatusCodeCount; ++i)
    if (kNames[i] == name) return static_cast<StatusCode>(i);
  return std::nullopt;
}

std::optional<StatusCode> statusCodeFromValue(std::uint32_t value) {
  if (value < kStatusCodeCount) return static_cast<StatusCode>(value);
  return std::nullopt;
}

bool compatible(std::uint16_t client_major, std::uint16_t client_minor, std::uint16_t server_major,
                std::uint16_t server_minor) {
  return client_major == server_major && client_minor <= server_minor;
}

Status checkSchemaVersion(std::uint16_t client_major, std::uint16_t client_minor, std::uint16_t server_major,
                          std::uint16_t server_minor) {
  if (compatible(client_major, client_minor, server_major, server_minor)) return {};
  const std::string client = versionString(client_major, client_minor);
  const std::string server = versionString(server_major, server_minor);
  std::string message = "schema version mismatch: the client speaks robodiff schema " + client +
                        ", this server speaks " + server + "; ";
  if (client_major != server_major)
    message += "the major versions differ, so client and server must be built against the same major version";
  else
    message += "the client is newer than the server: upgrade robodiffd to schema " + client +
               " or later, or use a client built against schema " + server + " or older";
  return {StatusCode::FailedPrecondition, std::move(message)};
}

}  // namespace robodiff
