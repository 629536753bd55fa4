// Fuzz target: the iceoryx wire codec (schema/shm) on the bytes another process puts in
// shared memory. Byte 0 picks the mode:
// - even: the rest is a whole chunk, copied to an 8-byte aligned buffer as iceoryx hands
//   it over, read as robodiffd reads a request (parseRequest, then the body's decoder
//   for its method) and as a client reads a reply (parseReply, then its decoder);
// - odd: the rest is a body alone and byte 1 picks which of the 22 message decoders
//   reads it (a shortcut past the 176-byte header).
// A body that decodes is encoded again and decoded again, and the two encodings must be
// equal (one message, one encoding).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "robodiff/schema/shm_codec.hpp"

namespace {

namespace shm = robodiff::shm;
namespace rpc = robodiff::rpc;

// An 8-byte aligned copy of the bytes, as a chunk in shared memory is.
struct AlignedCopy {
  explicit AlignedCopy(std::span<const std::uint8_t> bytes) : words((bytes.size() + 7) / 8), size(bytes.size()) {
    if (size) std::memcpy(words.data(), bytes.data(), size);
  }
  std::span<const std::byte> span() const { return {reinterpret_cast<const std::byte*>(words.data()), size}; }
  std::vector<std::uint64_t> words;
  std::size_t size;
};

template <class Message>
void decodeAndRoundTrip(std::span<const std::byte> body) {
  Message message;
  if (!shm::decode(body, message).ok()) return;
  const std::vector<std::byte> first = shm::encode(message);
  const AlignedCopy copy({reinterpret_cast<const std::uint8_t*>(first.data()), first.size()});
  Message again;
  if (!shm::decode(copy.span(), again).ok()) {
    std::fprintf(stderr, "a body this codec encoded does not decode\n");
    std::abort();
  }
  if (shm::encode(again) != first) {
    std::fprintf(stderr, "decode(encode(x)) encodes differently from x\n");
    std::abort();
  }
}

void decodeRequestBody(rpc::Method method, std::span<const std::byte> body) {
  switch (method) {
    case rpc::Method::LoadModel: return decodeAndRoundTrip<rpc::LoadModelRequest>(body);
    case rpc::Method::GetFunction: return decodeAndRoundTrip<rpc::GetFunctionRequest>(body);
    case rpc::Method::Evaluate: {
      shm::EvaluateRequestView view;
      (void)shm::decodeEvaluateRequest(body, view);
      return decodeAndRoundTrip<rpc::EvaluateRequest>(body);
    }
    case rpc::Method::EvaluateBatch: {
      shm::EvaluateRequestView view;
      (void)shm::decodeEvaluateRequest(body, view);
      return decodeAndRoundTrip<rpc::EvaluateBatchRequest>(body);
    }
    case rpc::Method::ListFunctions: return decodeAndRoundTrip<rpc::ListFunctionsRequest>(body);
    case rpc::Method::Health: return decodeAndRoundTrip<rpc::HealthRequest>(body);
    case rpc::Method::Release: return decodeAndRoundTrip<rpc::ReleaseRequest>(body);
    case rpc::Method::SubmitJob: return decodeAndRoundTrip<rpc::SubmitJobRequest>(body);
    case rpc::Method::JobStatus: return decodeAndRoundTrip<rpc::JobStatusRequest>(body);
    case rpc::Method::CancelJob: return decodeAndRoundTrip<rpc::CancelJobRequest>(body);
    case rpc::Method::JobResult: return decodeAndRoundTrip<rpc::JobResultRequest>(body);
    case rpc::Method::QueryArtifact: return decodeAndRoundTrip<rpc::QueryArtifactRequest>(body);
    case rpc::Method::FetchArtifactChunk: return decodeAndRoundTrip<rpc::FetchArtifactChunkRequest>(body);
    case rpc::Method::FleetStatus: return decodeAndRoundTrip<rpc::FleetStatusRequest>(body);
  }
}

void decodeReplyBody(rpc::Method method, std::span<const std::byte> body) {
  switch (method) {
    case rpc::Method::LoadModel: return decodeAndRoundTrip<rpc::LoadModelReply>(body);
    case rpc::Method::GetFunction: return decodeAndRoundTrip<rpc::GetFunctionReply>(body);
    case rpc::Method::Evaluate: {
      shm::EvaluateReplyView view;
      (void)shm::decodeEvaluateReply(body, view);
      return decodeAndRoundTrip<rpc::EvaluateReply>(body);
    }
    case rpc::Method::EvaluateBatch: {
      shm::EvaluateReplyView view;
      (void)shm::decodeEvaluateReply(body, view);
      return decodeAndRoundTrip<rpc::EvaluateBatchReply>(body);
    }
    case rpc::Method::ListFunctions: return decodeAndRoundTrip<rpc::ListFunctionsReply>(body);
    case rpc::Method::Health: return decodeAndRoundTrip<rpc::HealthReply>(body);
    case rpc::Method::Release: return decodeAndRoundTrip<rpc::ReleaseReply>(body);
    case rpc::Method::SubmitJob: return decodeAndRoundTrip<rpc::SubmitJobReply>(body);
    case rpc::Method::JobStatus: return decodeAndRoundTrip<rpc::JobStatusReply>(body);
    case rpc::Method::CancelJob: return decodeAndRoundTrip<rpc::CancelJobReply>(body);
    case rpc::Method::JobResult: return decodeAndRoundTrip<rpc::JobResultReply>(body);
    case rpc::Method::QueryArtifact: return decodeAndRoundTrip<rpc::QueryArtifactReply>(body);
    case rpc::Method::FetchArtifactChunk: return decodeAndRoundTrip<rpc::FetchArtifactChunkReply>(body);
    case rpc::Method::FleetStatus: return decodeAndRoundTrip<rpc::FleetStatusReply>(body);
  }
}

void chunk(std::span<const std::uint8_t> bytes) {
  const AlignedCopy copy(bytes);
  const void* data = copy.words.data();
  shm::RequestView request;
  if (shm::parseRequest(data, copy.size, request).ok()) decodeRequestBody(request.method, request.body);
  shm::ReplyView reply;
  if (shm::parseReply(data, copy.size, reply).ok()) decodeReplyBody(reply.method, reply.body);
}

void body(std::uint8_t selector, std::span<const std::uint8_t> bytes) {
  const AlignedCopy copy(bytes);
  const auto method = static_cast<rpc::Method>((selector >> 1) % rpc::kMethodCount);
  if (selector & 1)
    decodeReplyBody(method, copy.span());
  else
    decodeRequestBody(method, copy.span());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::span<const std::uint8_t> rest(data + 1, size - 1);
  if ((data[0] & 1) == 0)
    chunk(rest);
  else if (!rest.empty())
    body(rest[0], rest.subspan(1));
  return 0;
}
