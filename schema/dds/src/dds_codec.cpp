// The DDS codec: rpc messages <-> idlc-generated C types. Every allocation is dds_alloc /
// dds_string_dup so that dds_sample_free(DDS_FREE_CONTENTS) releases it (see dds_codec.hpp).
#include "robodiff/schema/dds_codec.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace robodiff::dds_codec {

// ---- small pieces --------------------------------------------------------------------

char* dupString(std::string_view text) {
  char* out = static_cast<char*>(dds_alloc(text.size() + 1));
  if (!text.empty()) std::memcpy(out, text.data(), text.size());
  out[text.size()] = '\0';
  return out;
}

std::string toString(const char* text) { return text ? std::string(text) : std::string(); }

void allocDoubles(dds_sequence_double& sequence, std::size_t count) {
  sequence._buffer = count ? static_cast<double*>(dds_alloc(count * sizeof(double))) : nullptr;
  sequence._length = sequence._maximum = static_cast<uint32_t>(count);
  sequence._release = true;
}

void borrowDoubles(dds_sequence_double& sequence, std::span<const double> values) {
  sequence._buffer = const_cast<double*>(values.data());  // only read by dds_write
  sequence._length = sequence._maximum = static_cast<uint32_t>(values.size());
  sequence._release = false;
}

void detachDoubles(dds_sequence_double& sequence) {
  sequence._buffer = nullptr;
  sequence._length = sequence._maximum = 0;
  sequence._release = false;
}

StatusCode statusFromWire(robodiff_wire_StatusCode code) {
  return statusCodeFromValue(static_cast<std::uint32_t>(code)).value_or(StatusCode::Unknown);
}

std::optional<rpc::Method> methodFromWire(robodiff_wire_Method method) {
  const auto value = static_cast<std::uint32_t>(method);
  if (value >= rpc::kMethodCount) return std::nullopt;
  return static_cast<rpc::Method>(value);
}

namespace {

// Sequences of plain values (doubles, unsigned longs, octets): one dds_alloc'd copy.
template <class Seq, class T>
void copyToWire(const std::vector<T>& in, Seq& out) {
  using Element = std::remove_pointer_t<decltype(out._buffer)>;
  static_assert(sizeof(Element) == sizeof(T));
  out._buffer = in.empty() ? nullptr : static_cast<Element*>(dds_alloc(in.size() * sizeof(T)));
  if (!in.empty()) std::memcpy(out._buffer, in.data(), in.size() * sizeof(T));
  out._length = out._maximum = static_cast<uint32_t>(in.size());
  out._release = true;
}

template <class Seq, class T>
void copyFromWire(const Seq& in, std::vector<T>& out) {
  out.assign(in._buffer, in._buffer ? in._buffer + in._length : in._buffer);
}

// Sequences of structs or strings: allocate the buffer zeroed, convert element by element.
template <class Seq, class T, class Convert>
void mapToWire(const std::vector<T>& in, Seq& out, Convert convert) {
  using Element = std::remove_pointer_t<decltype(out._buffer)>;
  out._buffer = in.empty() ? nullptr : static_cast<Element*>(dds_alloc(in.size() * sizeof(Element)));
  if (!in.empty()) std::memset(static_cast<void*>(out._buffer), 0, in.size() * sizeof(Element));
  out._length = out._maximum = static_cast<uint32_t>(in.size());
  out._release = true;
  for (std::size_t i = 0; i < in.size(); ++i) convert(in[i], out._buffer[i]);
}

template <class Seq, class T, class Convert>
void mapFromWire(const Seq& in, std::vector<T>& out, Convert convert) {
  out.clear();
  if (!in._buffer) return;
  out.resize(in._length);
  for (uint32_t i = 0; i < in._length; ++i) convert(in._buffer[i], out[i]);
}

// ---- every message, derived from its field list ---------------------------------------

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

template <class T, class W>
void put(const T& in, W& out) {
  if constexpr (std::is_same_v<T, std::string>) {
    out = dupString(in);
  } else if constexpr (std::is_enum_v<T>) {
    out = static_cast<W>(static_cast<std::uint32_t>(in));
  } else if constexpr (std::is_arithmetic_v<T>) {
    out = in;
  } else if constexpr (IsVector<T>::value) {
    using Element = typename T::value_type;
    if constexpr (std::is_arithmetic_v<Element>) copyToWire(in, out);
    else mapToWire(in, out, [](const Element& i, auto& o) { put(i, o); });
  } else {
    rpc::Fields<T>::visit(in, out, [](const char*, const auto& i, auto& o) { put(i, o); });
  }
}

template <class W, class T>
void get(const W& in, T& out) {
  if constexpr (std::is_same_v<T, std::string>) {
    out = toString(in);
  } else if constexpr (std::is_same_v<T, StatusCode>) {
    out = statusFromWire(in);
  } else if constexpr (std::is_enum_v<T>) {
    out = static_cast<T>(static_cast<std::uint32_t>(in));
  } else if constexpr (std::is_arithmetic_v<T>) {
    out = in;
  } else if constexpr (IsVector<T>::value) {
    using Element = typename T::value_type;
    if constexpr (std::is_arithmetic_v<Element>) copyFromWire(in, out);
    else mapFromWire(in, out, [](const auto& i, Element& o) { get(i, o); });
  } else {
    rpc::Fields<T>::visit(out, in, [](const char*, auto& o, const auto& i) { get(i, o); });
  }
}

}  // namespace

template <class Message, class Wire>
void toWire(const Message& in, Wire& out) {
  put(in, out);
}
template <class Wire, class Message>
void fromWire(const Wire& in, Message& out) {
  get(in, out);
}

#define ROBODIFF_DDS_CODEC(Message)                                                 \
  template void toWire(const rpc::Message& in, robodiff_wire_##Message& out);       \
  template void fromWire(const robodiff_wire_##Message& in, rpc::Message& out);
ROBODIFF_RPC_MESSAGES(ROBODIFF_DDS_CODEC)
#undef ROBODIFF_DDS_CODEC

// ---- headers -------------------------------------------------------------------------

void toWire(const rpc::RequestHeader& h, robodiff_wire_RequestHeader& out) { put(h, out); }
void toWire(const rpc::ReplyHeader& h, robodiff_wire_ReplyHeader& out) { put(h, out); }

rpc::RequestHeader fromWire(const robodiff_wire_RequestHeader& h) {
  rpc::RequestHeader out;
  get(h, out);
  return out;
}
rpc::ReplyHeader fromWire(const robodiff_wire_ReplyHeader& h) {
  rpc::ReplyHeader out;
  get(h, out);
  return out;
}

// ---- envelopes -------------------------------------------------------------------------

namespace {

// Body variant -> union: the variant index is the discriminator (same order as Method).
template <class Body, class Union>
void bodyToWire(const Body& body, Union& out) {
  out._d = static_cast<robodiff_wire_Method>(body.index());
  std::visit(
      [&](const auto& message) {
        using M = std::decay_t<decltype(message)>;
        if constexpr (std::is_same_v<M, rpc::LoadModelRequest> || std::is_same_v<M, rpc::LoadModelReply>)
          toWire(message, out._u.load_model);
        else if constexpr (std::is_same_v<M, rpc::GetFunctionRequest> || std::is_same_v<M, rpc::GetFunctionReply>)
          toWire(message, out._u.get_function);
        else if constexpr (std::is_same_v<M, rpc::EvaluateRequest> || std::is_same_v<M, rpc::EvaluateReply>)
          toWire(message, out._u.evaluate);
        else if constexpr (std::is_same_v<M, rpc::EvaluateBatchRequest> || std::is_same_v<M, rpc::EvaluateBatchReply>)
          toWire(message, out._u.evaluate_batch);
        else if constexpr (std::is_same_v<M, rpc::ListFunctionsRequest> ||
                           std::is_same_v<M, rpc::ListFunctionsReply>)
          toWire(message, out._u.list_functions);
        else if constexpr (std::is_same_v<M, rpc::HealthRequest> || std::is_same_v<M, rpc::HealthReply>)
          toWire(message, out._u.health);
        else if constexpr (std::is_same_v<M, rpc::ReleaseRequest> || std::is_same_v<M, rpc::ReleaseReply>)
          toWire(message, out._u.release);
        else if constexpr (std::is_same_v<M, rpc::SubmitJobRequest> || std::is_same_v<M, rpc::SubmitJobReply>)
          toWire(message, out._u.submit_job);
        else if constexpr (std::is_same_v<M, rpc::JobStatusRequest> || std::is_same_v<M, rpc::JobStatusReply>)
          toWire(message, out._u.job_status);
        else if constexpr (std::is_same_v<M, rpc::CancelJobRequest> || std::is_same_v<M, rpc::CancelJobReply>)
          toWire(message, out._u.cancel_job);
        else if constexpr (std::is_same_v<M, rpc::JobResultRequest> || std::is_same_v<M, rpc::JobResultReply>)
          toWire(message, out._u.job_result);
        else if constexpr (std::is_same_v<M, rpc::QueryArtifactRequest> ||
                           std::is_same_v<M, rpc::QueryArtifactReply>)
          toWire(message, out._u.query_artifact);
        else if constexpr (std::is_same_v<M, rpc::FetchArtifactChunkRequest> ||
                           std::is_same_v<M, rpc::FetchArtifactChunkReply>)
          toWire(message, out._u.fetch_artifact_chunk);
        else if constexpr (std::is_same_v<M, rpc::FleetStatusRequest> || std::is_same_v<M, rpc::FleetStatusReply>)
          toWire(message, out._u.fleet_status);
        else
          static_assert(sizeof(M) == 0, "a body alternative with no union member here");
      },
      body);
}

template <class Body, class Union>
Status bodyFromWire(const Union& in, Body& out) {
  const auto method = methodFromWire(in._d);
  if (!method)
    return {StatusCode::InvalidArgument,
            "unknown method " + std::to_string(static_cast<std::uint32_t>(in._d)) +
                " in the body's discriminator (this server knows 0.." + std::to_string(rpc::kMethodCount - 1) +
                "; is the client newer?)"};
  switch (*method) {
    case rpc::Method::LoadModel: fromWire(in._u.load_model, out.template emplace<0>()); break;
    case rpc::Method::GetFunction: fromWire(in._u.get_function, out.template emplace<1>()); break;
    case rpc::Method::Evaluate: fromWire(in._u.evaluate, out.template emplace<2>()); break;
    case rpc::Method::EvaluateBatch: fromWire(in._u.evaluate_batch, out.template emplace<3>()); break;
    case rpc::Method::ListFunctions: fromWire(in._u.list_functions, out.template emplace<4>()); break;
    case rpc::Method::Health: fromWire(in._u.health, out.template emplace<5>()); break;
    case rpc::Method::Release: fromWire(in._u.release, out.template emplace<6>()); break;
    case rpc::Method::SubmitJob: fromWire(in._u.submit_job, out.template emplace<7>()); break;
    case rpc::Method::JobStatus: fromWire(in._u.job_status, out.template emplace<8>()); break;
    case rpc::Method::CancelJob: fromWire(in._u.cancel_job, out.template emplace<9>()); break;
    case rpc::Method::JobResult: fromWire(in._u.job_result, out.template emplace<10>()); break;
    case rpc::Method::QueryArtifact: fromWire(in._u.query_artifact, out.template emplace<11>()); break;
    case rpc::Method::FetchArtifactChunk: fromWire(in._u.fetch_artifact_chunk, out.template emplace<12>()); break;
    case rpc::Method::FleetStatus: fromWire(in._u.fleet_status, out.template emplace<13>()); break;
  }
  return {};
}

}  // namespace

void toWire(const RequestBody& body, robodiff_wire_RequestBody& out) { bodyToWire(body, out); }
void toWire(const ReplyBody& body, robodiff_wire_ReplyBody& out) { bodyToWire(body, out); }
Status fromWire(const robodiff_wire_RequestBody& body, RequestBody& out) { return bodyFromWire(body, out); }
Status fromWire(const robodiff_wire_ReplyBody& body, ReplyBody& out) { return bodyFromWire(body, out); }

ReplyBody emptyReplyBody(rpc::Method method) {
  switch (method) {
    case rpc::Method::LoadModel: return rpc::LoadModelReply{};
    case rpc::Method::GetFunction: return rpc::GetFunctionReply{};
    case rpc::Method::Evaluate: return rpc::EvaluateReply{};
    case rpc::Method::EvaluateBatch: return rpc::EvaluateBatchReply{};
    case rpc::Method::ListFunctions: return rpc::ListFunctionsReply{};
    case rpc::Method::Health: return rpc::HealthReply{};
    case rpc::Method::Release: return rpc::ReleaseReply{};
    case rpc::Method::SubmitJob: return rpc::SubmitJobReply{};
    case rpc::Method::JobStatus: return rpc::JobStatusReply{};
    case rpc::Method::CancelJob: return rpc::CancelJobReply{};
    case rpc::Method::JobResult: return rpc::JobResultReply{};
    case rpc::Method::QueryArtifact: return rpc::QueryArtifactReply{};
    case rpc::Method::FetchArtifactChunk: return rpc::FetchArtifactChunkReply{};
    case rpc::Method::FleetStatus: return rpc::FleetStatusReply{};
  }
  return rpc::HealthReply{};
}

}  // namespace robodiff::dds_codec
