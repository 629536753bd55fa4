#pragma once
// The iceoryx transport's flat chunk layout, and the codec between it and the C++ messages
// of messages.hpp (the DDS transport carries the same messages as idlc C types).
//
// A chunk (one iceoryx request or response payload, 8-byte aligned) is:
//
//   ChunkHeader (176 bytes, fixed)                   magic, schema version, kind, method,
//                                                    correlation id, deadline budget, ids,
//                                                    status code, lengths
//   status message (status_message_length bytes, replies only), zero-padded to 8
//   body (body_length bytes)
//
// Evaluate / EvaluateBatch bodies are a small fixed part, the function id (requests),
// then the doubles, 8-byte aligned: the server evaluates straight from the request chunk
// into the response chunk. The other methods' bodies are the message encoded compactly:
// u8 booleans, u8 / u32 / u64 / f64 numbers (native byte order: shared memory never leaves the
// host), strings and sequences as a u32 count then the elements, every field in the
// order of messages.hpp.
//
// Decoding checks every length against the chunk's size and every enum against its
// range: a malformed chunk is INVALID_ARGUMENT with a message naming the problem, never an
// out-of-bounds read.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "robodiff/schema/messages.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::shm {

inline constexpr std::uint32_t kChunkMagic = 0x4D534452;  // "RDSM" in memory (little endian)
inline constexpr std::size_t kIdCapacity = 64;            // client / server ids: 63 chars + NUL
inline constexpr std::size_t kMaxStatusMessage = 4096;    // longer messages are cut
inline constexpr std::size_t kChunkAlignment = 8;

// SessionOpen / SessionReply: the handshake on the shared port ("robodiff", service, "rpc")
// that gives a connection its own request queue (server/shm: sessions; docs/transports.md).
enum class ChunkKind : std::uint16_t { Request = 1, Reply = 2, SessionOpen = 3, SessionReply = 4 };

struct ChunkHeader {
  std::uint32_t magic;
  std::uint16_t schema_major;
  std::uint16_t schema_minor;
  std::uint16_t kind;                    // ChunkKind
  std::uint16_t reserved;
  std::uint32_t method;                  // rpc::Method
  std::uint64_t correlation_id;
  std::uint64_t deadline_budget_ns;      // requests; 0 = none
  char client_id[kIdCapacity];           // NUL-terminated
  char server_instance_id[kIdCapacity];  // requests: the server asked (empty = any); replies: the server's
  std::uint32_t status_code;             // replies
  std::uint32_t status_message_length;   // replies: bytes of the message after the header
  std::uint64_t body_length;             // bytes of the body
};
static_assert(sizeof(ChunkHeader) == 176 && sizeof(ChunkHeader) % kChunkAlignment == 0);

// Evaluate / EvaluateBatch request body: this, the function id zero-padded to 8, then
// value_count doubles (knot_count knots of the function's inputs).
struct EvaluateRequestFixed {
  std::uint32_t function_id_length;
  std::uint32_t reserved;
  std::uint64_t knot_count;              // 1 for Evaluate
  std::uint64_t value_count;
};
// Evaluate / EvaluateBatch reply body: this, then value_count doubles.
struct EvaluateReplyFixed {
  std::uint32_t chunk_index = 0;
  std::uint32_t chunk_count = 1;
  std::uint32_t total_knots = 1;
  std::uint32_t first_knot = 0;
  std::uint32_t knot_count = 1;
  std::uint32_t reserved = 0;
  std::uint64_t value_count = 0;
};
static_assert(sizeof(EvaluateRequestFixed) == 24 && sizeof(EvaluateReplyFixed) == 32);

constexpr std::size_t align8(std::size_t n) { return (n + 7) & ~std::size_t{7}; }
// Where the body starts, and the whole chunk's size.
constexpr std::size_t bodyOffset(std::size_t status_message_length) {
  return sizeof(ChunkHeader) + align8(status_message_length);
}
constexpr std::size_t chunkSize(std::size_t status_message_length, std::size_t body_length) {
  return bodyOffset(status_message_length) + body_length;
}
std::size_t evaluateRequestBodySize(std::size_t function_id_length, std::uint64_t value_count);
std::size_t evaluateReplyBodySize(std::uint64_t value_count);
// The status message as it goes on the wire (cut to kMaxStatusMessage).
std::string_view wireMessage(const Status& status);

// ---- writing ----------------------------------------------------------------------------

// INVALID_ARGUMENT when `id` does not fit a header's id field (kIdCapacity - 1 chars).
Status checkId(std::string_view what, std::string_view id);

// Fill the header of a chunk of at least chunkSize(0, body_length) bytes. Ids must pass
// checkId (longer ones are cut).
void writeRequestHeader(void* chunk, const rpc::RequestHeader& header, rpc::Method method,
                        std::uint64_t body_length);
// Header and status message of a reply chunk of chunkSize(wireMessage(status).size(), body_length) bytes.
void writeReplyHeader(void* chunk, const rpc::ReplyHeader& header, rpc::Method method, std::uint64_t body_length);
// The body of a chunk whose header is written.
std::byte* bodyOf(void* chunk);

// Writes the fixed part and the function id; returns where the value_count input doubles go.
std::span<double> writeEvaluateRequestBody(std::byte* body, std::string_view function_id, std::uint64_t knots,
                                           std::uint64_t value_count);
// Writes the fixed part; returns where its value_count output doubles go.
std::span<double> writeEvaluateReplyBody(std::byte* body, const EvaluateReplyFixed& fixed);

// ---- reading ----------------------------------------------------------------------------

struct RequestView {
  rpc::RequestHeader header;
  rpc::Method method = rpc::Method::Health;
  std::span<const std::byte> body;       // inside the chunk
};
struct ReplyView {
  rpc::ReplyHeader header;
  rpc::Method method = rpc::Method::Health;
  std::span<const std::byte> body;       // inside the chunk
};
// Validates magic, kind, method, id termination and lengths against chunk_size.
Status parseRequest(const void* chunk, std::size_t chunk_size, RequestView& view);
Status parseReply(const void* chunk, std::size_t chunk_size, ReplyView& view);

// ---- sessions -----------------------------------------------------------------------------
// A session open is a request header of kind SessionOpen with method Health and no body
// (chunkSize(0, 0) bytes); its reply one of kind SessionReply whose body, when the status
// is OK, is the iceoryx event of the session's own service ("robodiff", service, event).
inline constexpr std::size_t kSessionEventCapacity = 100;  // iceoryx's IdString_t
void writeSessionOpen(void* chunk, const rpc::RequestHeader& header);
// A reply of chunkSize(wireMessage(header.status).size(), event.size()) bytes.
void writeSessionReply(void* chunk, const rpc::ReplyHeader& header, std::string_view event);
Status parseSessionOpen(const void* chunk, std::size_t chunk_size, RequestView& view);
// view.body is the event (empty unless the status is OK).
Status parseSessionReply(const void* chunk, std::size_t chunk_size, ReplyView& view);

struct EvaluateRequestView {
  std::string_view function_id;
  std::uint64_t knots = 0;
  std::span<const double> inputs;        // inside the chunk
};
struct EvaluateReplyView {
  EvaluateReplyFixed fixed;
  std::span<const double> outputs;       // inside the chunk
};
Status decodeEvaluateRequest(std::span<const std::byte> body, EvaluateRequestView& view);
Status decodeEvaluateReply(std::span<const std::byte> body, EvaluateReplyView& view);

// ---- whole messages -------------------------------------------------------------------

// encode(message) / decode(body, message) for every message of ROBODIFF_RPC_MESSAGES
// (messages.hpp). The Evaluate ones take the layout above (copies, for tests and tools:
// the transport uses the views; the vectors' storage is 8-byte aligned); the others are
// encoded compactly, field by field as their field lists say (compact_body.hpp).
template <class Message>
std::vector<std::byte> encode(const Message& message);
template <class Message>
Status decode(std::span<const std::byte> body, Message& message);

}  // namespace robodiff::shm
