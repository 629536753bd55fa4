// The flat chunk layout of the iceoryx transport: headers, Evaluate bodies in place, and
// the compact encoding of the other messages (see shm_codec.hpp).
#include "robodiff/schema/shm_codec.hpp"

#include "compact_body.hpp"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

namespace robodiff::shm {
namespace {

Status invalid(std::string message) { return {StatusCode::InvalidArgument, "malformed shared-memory chunk: " + std::move(message)}; }

void copyId(char (&field)[kIdCapacity], std::string_view id) {
  std::memset(field, 0, kIdCapacity);
  std::memcpy(field, id.data(), std::min(id.size(), kIdCapacity - 1));
}

// An id field must be NUL-terminated inside its array.
bool readId(const char (&field)[kIdCapacity], std::string& out) {
  const void* end = std::memchr(field, 0, kIdCapacity);
  if (end == nullptr) return false;
  out.assign(field, static_cast<const char*>(end));
  return true;
}

// Common header checks; fills method, correlation id and the body span.
const char* kindName(ChunkKind kind) {
  switch (kind) {
    case ChunkKind::Request: return "request";
    case ChunkKind::Reply: return "reply";
    case ChunkKind::SessionOpen: return "session open";
    case ChunkKind::SessionReply: return "session reply";
  }
  return "?";
}

Status parseCommon(const void* chunk, std::size_t chunk_size, ChunkKind kind, ChunkHeader& h,
                   rpc::Method& method, std::span<const std::byte>& body) {
  if (chunk == nullptr) return invalid("no chunk");
  if (chunk_size < sizeof(ChunkHeader))
    return invalid(std::to_string(chunk_size) + " bytes, shorter than the " + std::to_string(sizeof(ChunkHeader)) +
                   "-byte header");
  std::memcpy(&h, chunk, sizeof h);  // a private copy: the checks below hold for what we use
  if (h.magic != kChunkMagic) return invalid("bad magic (not a robodiff chunk)");
  if (h.kind != static_cast<std::uint16_t>(kind))
    return invalid(std::string("expected a ") + kindName(kind) + " chunk, got kind " + std::to_string(h.kind) +
                   (h.kind == static_cast<std::uint16_t>(ChunkKind::SessionOpen) ? " (a session open)" : ""));
  if (h.method >= rpc::kMethodCount) return invalid("unknown method " + std::to_string(h.method));
  method = static_cast<rpc::Method>(h.method);
  if (h.status_message_length > kMaxStatusMessage)
    return invalid("status message length " + std::to_string(h.status_message_length) + " exceeds " +
                   std::to_string(kMaxStatusMessage));
  const std::size_t offset = bodyOffset(h.status_message_length);
  if (offset > chunk_size || h.body_length > chunk_size - offset)
    return invalid("lengths (message " + std::to_string(h.status_message_length) + ", body " +
                   std::to_string(h.body_length) + ") exceed the chunk's " + std::to_string(chunk_size) + " bytes");
  body = {static_cast<const std::byte*>(chunk) + offset, static_cast<std::size_t>(h.body_length)};
  return {};
}

}  // namespace

std::size_t evaluateRequestBodySize(std::size_t function_id_length, std::uint64_t value_count) {
  return sizeof(EvaluateRequestFixed) + align8(function_id_length) + value_count * sizeof(double);
}
std::size_t evaluateReplyBodySize(std::uint64_t value_count) {
  return sizeof(EvaluateReplyFixed) + value_count * sizeof(double);
}

std::string_view wireMessage(const Status& status) {
  return std::string_view(status.message).substr(0, kMaxStatusMessage);
}

Status checkId(std::string_view what, std::string_view id) {
  if (id.size() < kIdCapacity && id.find('\0') == std::string_view::npos) return {};
  return {StatusCode::InvalidArgument, std::string(what) + " '" + std::string(id.substr(0, 80)) + "' is " +
                                           std::to_string(id.size()) + " characters; the iceoryx transport allows at most " +
                                           std::to_string(kIdCapacity - 1) + " (and no NUL)"};
}

void writeRequestHeader(void* chunk, const rpc::RequestHeader& header, rpc::Method method, std::uint64_t body_length) {
  ChunkHeader h{};
  h.magic = kChunkMagic;
  h.schema_major = header.schema_version.major;
  h.schema_minor = header.schema_version.minor;
  h.kind = static_cast<std::uint16_t>(ChunkKind::Request);
  h.method = static_cast<std::uint32_t>(method);
  h.correlation_id = header.correlation_id;
  h.deadline_budget_ns = header.deadline_budget_ns;
  copyId(h.client_id, header.client_id);
  copyId(h.server_instance_id, header.server_instance_id);
  h.body_length = body_length;
  std::memcpy(chunk, &h, sizeof h);
}

void writeReplyHeader(void* chunk, const rpc::ReplyHeader& header, rpc::Method method, std::uint64_t body_length) {
  const std::string_view message = wireMessage(header.status);
  ChunkHeader h{};
  h.magic = kChunkMagic;
  h.schema_major = header.schema_version.major;
  h.schema_minor = header.schema_version.minor;
  h.kind = static_cast<std::uint16_t>(ChunkKind::Reply);
  h.method = static_cast<std::uint32_t>(method);
  h.correlation_id = header.correlation_id;
  copyId(h.client_id, header.client_id);
  copyId(h.server_instance_id, header.server_instance_id);
  h.status_code = static_cast<std::uint32_t>(header.status.code);
  h.status_message_length = static_cast<std::uint32_t>(message.size());
  h.body_length = body_length;
  auto* bytes = static_cast<std::byte*>(chunk);
  std::memcpy(bytes, &h, sizeof h);
  std::memcpy(bytes + sizeof h, message.data(), message.size());
  std::memset(bytes + sizeof h + message.size(), 0, align8(message.size()) - message.size());
}

std::byte* bodyOf(void* chunk) {
  ChunkHeader h;
  std::memcpy(&h, chunk, sizeof h);
  return static_cast<std::byte*>(chunk) + bodyOffset(h.status_message_length);
}

std::span<double> writeEvaluateRequestBody(std::byte* body, std::string_view function_id, std::uint64_t knots,
                                           std::uint64_t value_count) {
  EvaluateRequestFixed fixed{static_cast<std::uint32_t>(function_id.size()), 0, knots, value_count};
  std::memcpy(body, &fixed, sizeof fixed);
  std::byte* id = body + sizeof fixed;
  std::memcpy(id, function_id.data(), function_id.size());
  std::memset(id + function_id.size(), 0, align8(function_id.size()) - function_id.size());
  return {reinterpret_cast<double*>(id + align8(function_id.size())), static_cast<std::size_t>(value_count)};
}

std::span<double> writeEvaluateReplyBody(std::byte* body, const EvaluateReplyFixed& fixed) {
  std::memcpy(body, &fixed, sizeof fixed);
  return {reinterpret_cast<double*>(body + sizeof fixed), static_cast<std::size_t>(fixed.value_count)};
}

namespace {

Status parseRequestOf(ChunkKind kind, const void* chunk, std::size_t chunk_size, RequestView& view) {
  ChunkHeader h;
  if (auto s = parseCommon(chunk, chunk_size, kind, h, view.method, view.body); !s.ok()) return s;
  if (!readId(h.client_id, view.header.client_id)) return invalid("client id is not NUL-terminated");
  if (!readId(h.server_instance_id, view.header.server_instance_id))
    return invalid("server instance id is not NUL-terminated");
  if (h.status_message_length != 0) return invalid("a request carries no status message");
  view.header.schema_version = {h.schema_major, h.schema_minor};
  view.header.correlation_id = h.correlation_id;
  view.header.deadline_budget_ns = h.deadline_budget_ns;
  return {};
}

Status parseReplyOf(ChunkKind kind, const void* chunk, std::size_t chunk_size, ReplyView& view) {
  ChunkHeader h;
  if (auto s = parseCommon(chunk, chunk_size, kind, h, view.method, view.body); !s.ok()) return s;
  if (!readId(h.client_id, view.header.client_id)) return invalid("client id is not NUL-terminated");
  if (!readId(h.server_instance_id, view.header.server_instance_id))
    return invalid("server instance id is not NUL-terminated");
  view.header.schema_version = {h.schema_major, h.schema_minor};
  view.header.correlation_id = h.correlation_id;
  // A code this build does not know (a newer server) reads as UNKNOWN.
  view.header.status.code = statusCodeFromValue(h.status_code).value_or(StatusCode::Unknown);
  view.header.status.message.assign(static_cast<const char*>(chunk) + sizeof(ChunkHeader), h.status_message_length);
  return {};
}

void setKind(void* chunk, ChunkKind kind) {
  const auto value = static_cast<std::uint16_t>(kind);
  std::memcpy(static_cast<std::byte*>(chunk) + offsetof(ChunkHeader, kind), &value, sizeof value);
}

}  // namespace

Status parseRequest(const void* chunk, std::size_t chunk_size, RequestView& view) {
  return parseRequestOf(ChunkKind::Request, chunk, chunk_size, view);
}
Status parseReply(const void* chunk, std::size_t chunk_size, ReplyView& view) {
  return parseReplyOf(ChunkKind::Reply, chunk, chunk_size, view);
}

void writeSessionOpen(void* chunk, const rpc::RequestHeader& header) {
  writeRequestHeader(chunk, header, rpc::Method::Health, 0);
  setKind(chunk, ChunkKind::SessionOpen);
}
void writeSessionReply(void* chunk, const rpc::ReplyHeader& header, std::string_view event) {
  if (!header.status.ok()) event = {};
  writeReplyHeader(chunk, header, rpc::Method::Health, event.size());
  setKind(chunk, ChunkKind::SessionReply);
  std::memcpy(bodyOf(chunk), event.data(), event.size());
}
Status parseSessionOpen(const void* chunk, std::size_t chunk_size, RequestView& view) {
  if (auto s = parseRequestOf(ChunkKind::SessionOpen, chunk, chunk_size, view); !s.ok()) return s;
  if (!view.body.empty()) return invalid("a session open carries no body");
  return {};
}
Status parseSessionReply(const void* chunk, std::size_t chunk_size, ReplyView& view) {
  if (auto s = parseReplyOf(ChunkKind::SessionReply, chunk, chunk_size, view); !s.ok()) return s;
  if (view.body.size() > kSessionEventCapacity) return invalid("a session's event name is longer than 100 characters");
  return {};
}

Status decodeEvaluateRequest(std::span<const std::byte> body, EvaluateRequestView& view) {
  EvaluateRequestFixed fixed;
  if (body.size() < sizeof fixed) return invalid("Evaluate request body shorter than its fixed part");
  std::memcpy(&fixed, body.data(), sizeof fixed);
  const std::size_t rest = body.size() - sizeof fixed;
  if (fixed.function_id_length > rest || fixed.value_count > rest / sizeof(double) ||
      align8(fixed.function_id_length) + fixed.value_count * sizeof(double) != rest)
    return invalid("Evaluate request lengths (function id " + std::to_string(fixed.function_id_length) + ", " +
                   std::to_string(fixed.value_count) + " doubles) do not match its " + std::to_string(body.size()) +
                   "-byte body");
  const std::byte* id = body.data() + sizeof fixed;
  const std::byte* values = id + align8(fixed.function_id_length);
  if (reinterpret_cast<std::uintptr_t>(values) % alignof(double) != 0) return invalid("inputs are not 8-byte aligned");
  view.function_id = {reinterpret_cast<const char*>(id), fixed.function_id_length};
  view.knots = fixed.knot_count;
  view.inputs = {reinterpret_cast<const double*>(values), static_cast<std::size_t>(fixed.value_count)};
  return {};
}

Status decodeEvaluateReply(std::span<const std::byte> body, EvaluateReplyView& view) {
  if (body.size() < sizeof(EvaluateReplyFixed)) return invalid("Evaluate reply body shorter than its fixed part");
  std::memcpy(&view.fixed, body.data(), sizeof view.fixed);
  const std::size_t rest = body.size() - sizeof(EvaluateReplyFixed);
  if (view.fixed.value_count != rest / sizeof(double) || rest % sizeof(double) != 0)
    return invalid("Evaluate reply claims " + std::to_string(view.fixed.value_count) + " doubles in a " +
                   std::to_string(body.size()) + "-byte body");
  const std::byte* values = body.data() + sizeof(EvaluateReplyFixed);
  if (reinterpret_cast<std::uintptr_t>(values) % alignof(double) != 0) return invalid("outputs are not 8-byte aligned");
  view.outputs = {reinterpret_cast<const double*>(values), static_cast<std::size_t>(view.fixed.value_count)};
  return {};
}

// ---- Evaluate bodies as whole messages ------------------------------------------------------

static std::vector<std::byte> evaluateRequestBytes(std::string_view id, std::uint64_t knots,
                                                   const std::vector<double>& inputs) {
  std::vector<std::byte> bytes(evaluateRequestBodySize(id.size(), inputs.size()));
  auto values = writeEvaluateRequestBody(bytes.data(), id, knots, inputs.size());
  std::copy(inputs.begin(), inputs.end(), values.begin());
  return bytes;
}
static std::vector<std::byte> evaluateReplyBytes(const EvaluateReplyFixed& fixed, const std::vector<double>& outputs) {
  std::vector<std::byte> bytes(evaluateReplyBodySize(outputs.size()));
  auto values = writeEvaluateReplyBody(bytes.data(), fixed);
  std::copy(outputs.begin(), outputs.end(), values.begin());
  return bytes;
}

static std::vector<std::byte> encodeWhole(const rpc::EvaluateRequest& m) { return evaluateRequestBytes(m.function_id, 1, m.inputs); }
static std::vector<std::byte> encodeWhole(const rpc::EvaluateBatchRequest& m) {
  return evaluateRequestBytes(m.function_id, m.knot_count, m.inputs);
}
static std::vector<std::byte> encodeWhole(const rpc::EvaluateReply& m) {
  EvaluateReplyFixed fixed;
  fixed.value_count = m.outputs.size();
  return evaluateReplyBytes(fixed, m.outputs);
}
static std::vector<std::byte> encodeWhole(const rpc::EvaluateBatchReply& m) {
  EvaluateReplyFixed fixed{m.chunk_index, m.chunk_count, m.total_knots, m.first_knot, m.knot_count, 0, m.outputs.size()};
  return evaluateReplyBytes(fixed, m.outputs);
}

static Status decodeWhole(std::span<const std::byte> body, rpc::EvaluateRequest& m) {
  EvaluateRequestView view;
  if (auto s = decodeEvaluateRequest(body, view); !s.ok()) return s;
  if (view.knots != 1) return invalid("an Evaluate request carries one knot, not " + std::to_string(view.knots));
  m.function_id = std::string(view.function_id);
  m.inputs.assign(view.inputs.begin(), view.inputs.end());
  return {};
}
static Status decodeWhole(std::span<const std::byte> body, rpc::EvaluateBatchRequest& m) {
  EvaluateRequestView view;
  if (auto s = decodeEvaluateRequest(body, view); !s.ok()) return s;
  if (view.knots > std::numeric_limits<std::uint32_t>::max())
    return invalid("knot count " + std::to_string(view.knots) + " does not fit 32 bits");
  m.function_id = std::string(view.function_id);
  m.knot_count = static_cast<std::uint32_t>(view.knots);
  m.inputs.assign(view.inputs.begin(), view.inputs.end());
  return {};
}
static Status decodeWhole(std::span<const std::byte> body, rpc::EvaluateReply& m) {
  EvaluateReplyView view;
  if (auto s = decodeEvaluateReply(body, view); !s.ok()) return s;
  m.outputs.assign(view.outputs.begin(), view.outputs.end());
  return {};
}
static Status decodeWhole(std::span<const std::byte> body, rpc::EvaluateBatchReply& m) {
  EvaluateReplyView view;
  if (auto s = decodeEvaluateReply(body, view); !s.ok()) return s;
  m.chunk_index = view.fixed.chunk_index;
  m.chunk_count = view.fixed.chunk_count;
  m.total_knots = view.fixed.total_knots;
  m.first_knot = view.fixed.first_knot;
  m.knot_count = view.fixed.knot_count;
  m.outputs.assign(view.outputs.begin(), view.outputs.end());
  return {};
}

// ---- every message ---------------------------------------------------------------------------

template <class Message>
constexpr bool kIsEvaluate =
    std::is_same_v<Message, rpc::EvaluateRequest> || std::is_same_v<Message, rpc::EvaluateBatchRequest> ||
    std::is_same_v<Message, rpc::EvaluateReply> || std::is_same_v<Message, rpc::EvaluateBatchReply>;

template <class Message>
std::vector<std::byte> encode(const Message& message) {
  if constexpr (kIsEvaluate<Message>) {
    return encodeWhole(message);
  } else {
    compact::Writer w;
    compact::write(w, message);
    return w.take();
  }
}

template <class Message>
Status decode(std::span<const std::byte> body, Message& message) {
  if constexpr (kIsEvaluate<Message>) {
    return decodeWhole(body, message);
  } else {
    compact::Reader r(body);
    compact::read(r, "", message);
    return r.finish(rpc::Fields<Message>::kName);
  }
}

#define ROBODIFF_SHM_CODEC(Message)                                             \
  template std::vector<std::byte> encode(const rpc::Message& message);          \
  template Status decode(std::span<const std::byte> body, rpc::Message& message);
ROBODIFF_RPC_MESSAGES(ROBODIFF_SHM_CODEC)
#undef ROBODIFF_SHM_CODEC

}  // namespace robodiff::shm
