// The flat chunk layout of the iceoryx transport: headers, Evaluate bodies in place, and
// the compact encoding of the other messages (see shm_codec.hpp).
#include "robodiff/schema/shm_codec.hpp"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <limits>
#include <string>

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

// Appends numbers and strings in native byte order.
class Writer {
 public:
  void u8(std::uint8_t v) { raw(&v, 1); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void u32(std::uint32_t v) { raw(&v, sizeof v); }
  void u64(std::uint64_t v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void str(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    raw(s.data(), s.size());
  }
  template <class T, class F>
  void seq(const std::vector<T>& items, F&& each) {
    u32(static_cast<std::uint32_t>(items.size()));
    for (const auto& item : items) each(item);
  }
  std::vector<std::byte> take() { return std::move(bytes_); }

 private:
  void raw(const void* data, std::size_t size) {
    const auto* p = static_cast<const std::byte*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  std::vector<std::byte> bytes_;
};

// Reads what Writer wrote; every read checks the remaining length, the first failure
// sticks and names the field.
class Reader {
 public:
  explicit Reader(std::span<const std::byte> body) : body_(body) {}

  std::uint8_t u8(const char* field) { std::uint8_t v = 0; raw(&v, 1, field); return v; }
  bool boolean(const char* field) {
    const auto v = u8(field);
    if (v > 1) fail(std::string(field) + " is not a boolean (" + std::to_string(v) + ")");
    return v == 1;
  }
  std::uint32_t u32(const char* field) { std::uint32_t v = 0; raw(&v, sizeof v, field); return v; }
  std::uint64_t u64(const char* field) { std::uint64_t v = 0; raw(&v, sizeof v, field); return v; }
  double f64(const char* field) { double v = 0; raw(&v, sizeof v, field); return v; }
  std::string str(const char* field) {
    const auto size = u32(field);
    if (!ok()) return {};
    if (size > remaining()) {
      fail(std::string(field) + " claims " + std::to_string(size) + " bytes but only " +
           std::to_string(remaining()) + " remain");
      return {};
    }
    std::string s(reinterpret_cast<const char*>(body_.data() + pos_), size);
    pos_ += size;
    return s;
  }
  // A count of elements each at least min_element_bytes long (guards the allocation).
  std::uint32_t count(const char* field, std::size_t min_element_bytes) {
    const auto n = u32(field);
    if (ok() && std::uint64_t{n} * min_element_bytes > remaining()) {
      fail(std::string(field) + " claims " + std::to_string(n) + " elements but only " +
           std::to_string(remaining()) + " bytes remain");
      return 0;
    }
    return ok() ? n : 0;
  }
  template <class E>
  E enumeration(const char* field, std::uint32_t limit) {
    const auto v = u32(field);
    if (ok() && v >= limit) fail(std::string(field) + " has unknown value " + std::to_string(v));
    return static_cast<E>(ok() ? v : 0);
  }
  // OK only when every byte was read.
  Status finish(const char* message) {
    if (ok() && pos_ != body_.size())
      fail(std::to_string(body_.size() - pos_) + " unexpected trailing bytes");
    if (ok()) return {};
    return invalid(std::string(message) + ": " + error_);
  }
  bool ok() const { return error_.empty(); }
  void fail(std::string error) { if (ok()) error_ = std::move(error); }

 private:
  std::size_t remaining() const { return body_.size() - pos_; }
  void raw(void* out, std::size_t size, const char* field) {
    if (!ok()) return;
    if (size > remaining()) {
      fail(std::string(field) + " is cut off (" + std::to_string(remaining()) + " bytes left, " +
           std::to_string(size) + " needed)");
      return;
    }
    std::memcpy(out, body_.data() + pos_, size);
    pos_ += size;
  }
  std::span<const std::byte> body_;
  std::size_t pos_ = 0;
  std::string error_;
};

constexpr std::uint32_t kFunctionStates = 3, kOutputKinds = 3, kOutputLayouts = 2, kServingStates = 3;

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

// ---- compact bodies -----------------------------------------------------------------------

std::vector<std::byte> encode(const rpc::LoadModelRequest& m) {
  Writer w;
  w.str(m.urdf);
  w.boolean(m.floating_base);
  w.str(m.options_json);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::LoadModelRequest& m) {
  Reader r(body);
  m.urdf = r.str("urdf");
  m.floating_base = r.boolean("floating_base");
  m.options_json = r.str("options_json");
  return r.finish("LoadModelRequest");
}

static void writeStrings(Writer& w, const std::vector<std::string>& v) {
  w.seq(v, [&](const std::string& s) { w.str(s); });
}
static std::vector<std::string> readStrings(Reader& r, const char* field) {
  std::vector<std::string> v(r.count(field, 4));
  for (auto& s : v) s = r.str(field);
  return v;
}

std::vector<std::byte> encode(const rpc::LoadModelReply& m) {
  Writer w;
  w.str(m.model_id);
  writeStrings(w, m.joint_names);
  writeStrings(w, m.frame_names);
  w.u32(m.nq);
  w.u32(m.nv);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::LoadModelReply& m) {
  Reader r(body);
  m.model_id = r.str("model_id");
  m.joint_names = readStrings(r, "joint_names");
  m.frame_names = readStrings(r, "frame_names");
  m.nq = r.u32("nq");
  m.nv = r.u32("nv");
  return r.finish("LoadModelReply");
}

std::vector<std::byte> encode(const rpc::GetFunctionRequest& m) {
  Writer w;
  w.str(m.model_id);
  w.str(m.spec_json);
  w.boolean(m.wait);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::GetFunctionRequest& m) {
  Reader r(body);
  m.model_id = r.str("model_id");
  m.spec_json = r.str("spec_json");
  m.wait = r.boolean("wait");
  return r.finish("GetFunctionRequest");
}

std::vector<std::byte> encode(const rpc::GetFunctionReply& m) {
  Writer w;
  w.str(m.function_id);
  w.u32(static_cast<std::uint32_t>(m.state));
  w.seq(m.inputs, [&](const rpc::InputBlock& b) {
    w.str(b.name);
    w.u32(b.size);
  });
  w.seq(m.outputs, [&](const rpc::OutputBlock& b) {
    w.str(b.name);
    w.u32(static_cast<std::uint32_t>(b.kind));
    w.u32(b.rows);
    w.u32(b.cols);
    w.u32(static_cast<std::uint32_t>(b.layout));
    w.u32(b.nnz);
    w.seq(b.row_offsets, [&](std::uint32_t v) { w.u32(v); });
    w.seq(b.col_indices, [&](std::uint32_t v) { w.u32(v); });
  });
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::GetFunctionReply& m) {
  Reader r(body);
  m.function_id = r.str("function_id");
  m.state = r.enumeration<rpc::FunctionState>("state", kFunctionStates);
  m.inputs.assign(r.count("inputs", 8), {});
  for (auto& b : m.inputs) {
    b.name = r.str("inputs.name");
    b.size = r.u32("inputs.size");
  }
  m.outputs.assign(r.count("outputs", 32), {});
  for (auto& b : m.outputs) {
    b.name = r.str("outputs.name");
    b.kind = r.enumeration<rpc::OutputKind>("outputs.kind", kOutputKinds);
    b.rows = r.u32("outputs.rows");
    b.cols = r.u32("outputs.cols");
    b.layout = r.enumeration<rpc::OutputLayout>("outputs.layout", kOutputLayouts);
    b.nnz = r.u32("outputs.nnz");
    b.row_offsets.assign(r.count("outputs.row_offsets", 4), 0);
    for (auto& v : b.row_offsets) v = r.u32("outputs.row_offsets");
    b.col_indices.assign(r.count("outputs.col_indices", 4), 0);
    for (auto& v : b.col_indices) v = r.u32("outputs.col_indices");
  }
  return r.finish("GetFunctionReply");
}

std::vector<std::byte> encode(const rpc::ListFunctionsRequest& m) {
  Writer w;
  w.str(m.model_id);
  w.u32(m.page_size);
  w.str(m.page_token);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::ListFunctionsRequest& m) {
  Reader r(body);
  m.model_id = r.str("model_id");
  m.page_size = r.u32("page_size");
  m.page_token = r.str("page_token");
  return r.finish("ListFunctionsRequest");
}

std::vector<std::byte> encode(const rpc::ListFunctionsReply& m) {
  Writer w;
  w.seq(m.functions, [&](const rpc::FunctionSummary& f) {
    w.str(f.function_id);
    w.str(f.model_id);
    w.str(f.function_name);
    w.u32(static_cast<std::uint32_t>(f.state));
    w.boolean(f.compiled);
    w.u64(f.evaluations);
    w.str(f.message);
  });
  w.str(m.next_page_token);
  w.u32(m.total);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::ListFunctionsReply& m) {
  Reader r(body);
  m.functions.assign(r.count("functions", 29), {});
  for (auto& f : m.functions) {
    f.function_id = r.str("functions.function_id");
    f.model_id = r.str("functions.model_id");
    f.function_name = r.str("functions.function_name");
    f.state = r.enumeration<rpc::FunctionState>("functions.state", kFunctionStates);
    f.compiled = r.boolean("functions.compiled");
    f.evaluations = r.u64("functions.evaluations");
    f.message = r.str("functions.message");
  }
  m.next_page_token = r.str("next_page_token");
  m.total = r.u32("total");
  return r.finish("ListFunctionsReply");
}

std::vector<std::byte> encode(const rpc::HealthRequest& m) {
  Writer w;
  w.boolean(m.verbose);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::HealthRequest& m) {
  Reader r(body);
  m.verbose = r.boolean("verbose");
  return r.finish("HealthRequest");
}

std::vector<std::byte> encode(const rpc::HealthReply& m) {
  Writer w;
  w.u32(static_cast<std::uint32_t>(m.state));
  w.str(m.version);
  w.str(m.server_instance_id);
  w.u64(m.uptime_ns);
  for (std::uint32_t v : {m.models_loaded, m.functions_loaded, m.functions_compiled, m.builds_queued,
                          m.builds_running, m.builds_failed, m.builds_done})
    w.u32(v);
  for (std::uint64_t v : {m.cache_hits, m.cache_misses, m.cache_bytes, m.cache_entries}) w.u64(v);
  for (std::uint32_t v : {m.workers_total, m.workers_busy, m.queue_depth, m.queue_capacity, m.batch_threads})
    w.u32(v);
  w.seq(m.methods, [&](const rpc::MethodStats& s) {
    w.u32(static_cast<std::uint32_t>(s.method));
    for (std::uint64_t v : {s.requests, s.errors, s.p50_ns, s.p90_ns, s.p99_ns, s.max_ns}) w.u64(v);
  });
  w.seq(m.errors, [&](const rpc::StatusCount& c) {
    w.u32(static_cast<std::uint32_t>(c.code));
    w.u64(c.count);
  });
  w.seq(m.transports, [&](const rpc::TransportCounts& t) {
    w.str(t.transport);
    w.u64(t.requests);
    w.u64(t.errors);
  });
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::HealthReply& m) {
  Reader r(body);
  m.state = r.enumeration<rpc::ServingState>("state", kServingStates);
  m.version = r.str("version");
  m.server_instance_id = r.str("server_instance_id");
  m.uptime_ns = r.u64("uptime_ns");
  for (std::uint32_t* v : {&m.models_loaded, &m.functions_loaded, &m.functions_compiled, &m.builds_queued,
                           &m.builds_running, &m.builds_failed, &m.builds_done})
    *v = r.u32("counts");
  for (std::uint64_t* v : {&m.cache_hits, &m.cache_misses, &m.cache_bytes, &m.cache_entries}) *v = r.u64("cache");
  for (std::uint32_t* v : {&m.workers_total, &m.workers_busy, &m.queue_depth, &m.queue_capacity, &m.batch_threads})
    *v = r.u32("counts");
  m.methods.assign(r.count("methods", 52), {});
  for (auto& s : m.methods) {
    s.method = r.enumeration<rpc::Method>("methods.method", rpc::kMethodCount);
    for (std::uint64_t* v : {&s.requests, &s.errors, &s.p50_ns, &s.p90_ns, &s.p99_ns, &s.max_ns})
      *v = r.u64("methods.stats");
  }
  m.errors.assign(r.count("errors", 12), {});
  for (auto& c : m.errors) {
    c.code = r.enumeration<StatusCode>("errors.code", kStatusCodeCount);
    c.count = r.u64("errors.count");
  }
  m.transports.assign(r.count("transports", 20), {});
  for (auto& t : m.transports) {
    t.transport = r.str("transports.transport");
    t.requests = r.u64("transports.requests");
    t.errors = r.u64("transports.errors");
  }
  return r.finish("HealthReply");
}

std::vector<std::byte> encode(const rpc::ReleaseRequest& m) {
  Writer w;
  w.str(m.id);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::ReleaseRequest& m) {
  Reader r(body);
  m.id = r.str("id");
  return r.finish("ReleaseRequest");
}

std::vector<std::byte> encode(const rpc::ReleaseReply& m) {
  Writer w;
  w.u32(m.references_left);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::ReleaseReply& m) {
  Reader r(body);
  m.references_left = r.u32("references_left");
  return r.finish("ReleaseReply");
}

// ---- jobs -------------------------------------------------------------------------------

static void writeJobInfo(Writer& w, const rpc::JobInfo& m) {
  w.str(m.job_id);
  w.str(m.kind);
  w.u32(static_cast<std::uint32_t>(m.state));
  w.f64(m.progress);
  w.f64(m.elapsed_seconds);
  w.f64(m.eta_seconds);
  writeStrings(w, m.messages);
  w.str(m.error);
}
static void readJobInfo(Reader& r, rpc::JobInfo& m) {
  m.job_id = r.str("job_id");
  m.kind = r.str("kind");
  m.state = r.enumeration<rpc::JobState>("state", 5);
  m.progress = r.f64("progress");
  m.elapsed_seconds = r.f64("elapsed_seconds");
  m.eta_seconds = r.f64("eta_seconds");
  m.messages = readStrings(r, "messages");
  m.error = r.str("error");
}

std::vector<std::byte> encode(const rpc::SubmitJobRequest& m) {
  Writer w;
  w.str(m.kind);
  w.str(m.params_json);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::SubmitJobRequest& m) {
  Reader r(body);
  m.kind = r.str("kind");
  m.params_json = r.str("params_json");
  return r.finish("SubmitJobRequest");
}
std::vector<std::byte> encode(const rpc::SubmitJobReply& m) {
  Writer w;
  w.str(m.job_id);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::SubmitJobReply& m) {
  Reader r(body);
  m.job_id = r.str("job_id");
  return r.finish("SubmitJobReply");
}

// JobStatus, CancelJob and JobResult requests are a job id each.
template <class Request>
static std::vector<std::byte> encodeJobId(const Request& m) {
  Writer w;
  w.str(m.job_id);
  return w.take();
}
template <class Request>
static Status decodeJobId(std::span<const std::byte> body, Request& m, const char* what) {
  Reader r(body);
  m.job_id = r.str("job_id");
  return r.finish(what);
}
std::vector<std::byte> encode(const rpc::JobStatusRequest& m) { return encodeJobId(m); }
std::vector<std::byte> encode(const rpc::CancelJobRequest& m) { return encodeJobId(m); }
std::vector<std::byte> encode(const rpc::JobResultRequest& m) { return encodeJobId(m); }
Status decode(std::span<const std::byte> body, rpc::JobStatusRequest& m) {
  return decodeJobId(body, m, "JobStatusRequest");
}
Status decode(std::span<const std::byte> body, rpc::CancelJobRequest& m) {
  return decodeJobId(body, m, "CancelJobRequest");
}
Status decode(std::span<const std::byte> body, rpc::JobResultRequest& m) {
  return decodeJobId(body, m, "JobResultRequest");
}

std::vector<std::byte> encode(const rpc::JobStatusReply& m) {
  Writer w;
  w.seq(m.jobs, [&](const rpc::JobInfo& j) { writeJobInfo(w, j); });
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::JobStatusReply& m) {
  Reader r(body);
  m.jobs.assign(r.count("jobs", 48), {});
  for (auto& j : m.jobs) readJobInfo(r, j);
  return r.finish("JobStatusReply");
}
std::vector<std::byte> encode(const rpc::CancelJobReply& m) {
  Writer w;
  w.u32(static_cast<std::uint32_t>(m.state));
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::CancelJobReply& m) {
  Reader r(body);
  m.state = r.enumeration<rpc::JobState>("state", 5);
  return r.finish("CancelJobReply");
}
std::vector<std::byte> encode(const rpc::JobResultReply& m) {
  Writer w;
  writeJobInfo(w, m.info);
  w.str(m.result_json);
  w.str(m.result_dir);
  return w.take();
}
Status decode(std::span<const std::byte> body, rpc::JobResultReply& m) {
  Reader r(body);
  readJobInfo(r, m.info);
  m.result_json = r.str("result_json");
  m.result_dir = r.str("result_dir");
  return r.finish("JobResultReply");
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

std::vector<std::byte> encode(const rpc::EvaluateRequest& m) { return evaluateRequestBytes(m.function_id, 1, m.inputs); }
std::vector<std::byte> encode(const rpc::EvaluateBatchRequest& m) {
  return evaluateRequestBytes(m.function_id, m.knot_count, m.inputs);
}
std::vector<std::byte> encode(const rpc::EvaluateReply& m) {
  EvaluateReplyFixed fixed;
  fixed.value_count = m.outputs.size();
  return evaluateReplyBytes(fixed, m.outputs);
}
std::vector<std::byte> encode(const rpc::EvaluateBatchReply& m) {
  EvaluateReplyFixed fixed{m.chunk_index, m.chunk_count, m.total_knots, m.first_knot, m.knot_count, 0, m.outputs.size()};
  return evaluateReplyBytes(fixed, m.outputs);
}

Status decode(std::span<const std::byte> body, rpc::EvaluateRequest& m) {
  EvaluateRequestView view;
  if (auto s = decodeEvaluateRequest(body, view); !s.ok()) return s;
  if (view.knots != 1) return invalid("an Evaluate request carries one knot, not " + std::to_string(view.knots));
  m.function_id = std::string(view.function_id);
  m.inputs.assign(view.inputs.begin(), view.inputs.end());
  return {};
}
Status decode(std::span<const std::byte> body, rpc::EvaluateBatchRequest& m) {
  EvaluateRequestView view;
  if (auto s = decodeEvaluateRequest(body, view); !s.ok()) return s;
  if (view.knots > std::numeric_limits<std::uint32_t>::max())
    return invalid("knot count " + std::to_string(view.knots) + " does not fit 32 bits");
  m.function_id = std::string(view.function_id);
  m.knot_count = static_cast<std::uint32_t>(view.knots);
  m.inputs.assign(view.inputs.begin(), view.inputs.end());
  return {};
}
Status decode(std::span<const std::byte> body, rpc::EvaluateReply& m) {
  EvaluateReplyView view;
  if (auto s = decodeEvaluateReply(body, view); !s.ok()) return s;
  m.outputs.assign(view.outputs.begin(), view.outputs.end());
  return {};
}
Status decode(std::span<const std::byte> body, rpc::EvaluateBatchReply& m) {
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

}  // namespace robodiff::shm
