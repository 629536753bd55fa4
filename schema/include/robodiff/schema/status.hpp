#pragma once
// The service's status vocabulary (gRPC's codes) and the schema-version rule, in C++.
// Mirrors schema/robodiff.idl.in: StatusCode has the same numeric values as the generated
// robodiff_wire_StatusCode (checked by static_asserts in status.cpp and by the tests).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace robodiff {

// gRPC's codes with gRPC's numbers.
enum class StatusCode : std::uint32_t {
  Ok = 0,
  Cancelled = 1,
  Unknown = 2,
  InvalidArgument = 3,
  DeadlineExceeded = 4,
  NotFound = 5,
  AlreadyExists = 6,
  PermissionDenied = 7,
  ResourceExhausted = 8,
  FailedPrecondition = 9,
  Aborted = 10,
  OutOfRange = 11,
  Unimplemented = 12,
  Internal = 13,
  Unavailable = 14,
  DataLoss = 15,
  Unauthenticated = 16,
};
inline constexpr std::uint32_t kStatusCodeCount = 17;

// "OK", "INVALID_ARGUMENT", ...: the IDL / gRPC spelling. An out-of-range value gives
// "STATUS_CODE(<n>)".
std::string toString(StatusCode code);
// The inverse of toString for the 17 names (exact, upper case); nullopt otherwise.
std::optional<StatusCode> parseStatusCode(std::string_view name);
// nullopt when value is not one of the 17 codes (e.g. read off the wire from a newer peer).
std::optional<StatusCode> statusCodeFromValue(std::uint32_t value);

struct Status {
  StatusCode code = StatusCode::Ok;
  std::string message;  // for a person: what went wrong and what to do about it
  bool ok() const { return code == StatusCode::Ok; }
};

// The schema version this build speaks; robodiff.idl's SCHEMA_VERSION_MAJOR / MINOR are
// written from these. Bump MINOR for additions a server can ignore or answer (a new method,
// a new enum value at the end); bump MAJOR for anything else.
// 2.1: the artifact methods (QueryArtifact, FetchArtifactChunk) and FleetStatus.
// 2.0: ListFunctions paged (members added to @final ListFunctionsRequest / Reply) and
// iceoryx requests on a session per connection; 1.1 had added the job methods.
inline constexpr std::uint16_t kSchemaVersionMajor = 2;
inline constexpr std::uint16_t kSchemaVersionMinor = 1;

// The rule a server applies to a request's schema version: same major, and a client
// minor not newer than the server's (an older client only misses additions; a newer one
// may use what this server does not know).
bool compatible(std::uint16_t client_major, std::uint16_t client_minor,
                std::uint16_t server_major = kSchemaVersionMajor,
                std::uint16_t server_minor = kSchemaVersionMinor);

// OK when compatible; otherwise FAILED_PRECONDITION with a message naming both versions
// and what to upgrade.
Status checkSchemaVersion(std::uint16_t client_major, std::uint16_t client_minor,
                          std::uint16_t server_major = kSchemaVersionMajor,
                          std::uint16_t server_minor = kSchemaVersionMinor);

}  // namespace robodiff
