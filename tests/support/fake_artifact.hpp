// The artifact the transports' fake services serve (tests/dds and tests/shm
// fake_service.hpp): FetchArtifactChunk of "key-1", so that both transports carry the same
// bytes, zeros and 0xff runs included.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "robodiff/schema/messages.hpp"

namespace robodiff::testing {

// 300 bytes with runs of zeros and of 0xff.
inline std::vector<std::uint8_t> fakeArtifactPayload() {
  std::vector<std::uint8_t> bytes(300);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = i % 50 < 5 ? 0 : i % 50 < 10 ? 0xff : i * 37 % 256;
  return bytes;
}

// FetchArtifactChunk of artifact "key-1": 100 bytes a chunk unless asked for fewer.
inline Status fakeArtifactChunk(const rpc::FetchArtifactChunkRequest& request, rpc::FetchArtifactChunkReply& reply) {
  if (request.key != "key-1") return {StatusCode::NotFound, "no artifact " + request.key};
  const std::vector<std::uint8_t> payload = fakeArtifactPayload();
  const std::size_t from = static_cast<std::size_t>(std::min<std::uint64_t>(request.offset, payload.size()));
  const std::size_t n = std::min<std::size_t>(payload.size() - from, request.max_bytes ? request.max_bytes : 100);
  reply.offset = request.offset;
  reply.payload_bytes = payload.size();
  reply.data.assign(payload.begin() + from, payload.begin() + from + n);
  return {};
}

}  // namespace robodiff::testing
