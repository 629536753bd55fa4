#pragma once
// The shared-memory pools of the robodiff RouDi: deploy/roudi.toml lists the same pools
// (a test checks they agree), and the RouDi that robodiffd embeds when none is running is
// configured from this table.
//
// A mempool's size is iceoryx's "chunk payload": everything after iceoryx's own chunk
// header, i.e. the request/response header iceoryx puts first, alignment padding, and our
// payload. The largest pool (24 MiB) fits the largest batch the server accepts: 1,000
// knots of a 32-DoF function with ~3,000 outputs per knot = 24,000,000 bytes of doubles
// plus our header. Loaning more than the largest pool aborts the process inside iceoryx,
// so server and client check maxChunkPayload() before every loan.

#include <array>
#include <cstdint>

namespace robodiff::shm {

struct Mempool {
  std::uint32_t size;   // bytes per chunk (iceoryx chunk payload)
  std::uint32_t count;  // chunks
};

// Ascending sizes; keep deploy/roudi.toml equal. Total ~ 185 MiB of /dev/shm.
inline constexpr std::array<Mempool, 6> kMempools{{
    {1024, 1024},              // Health, Release, small Evaluate (~1 MiB)
    {16 * 1024, 512},          // Evaluate of a large function, LoadModel replies (8 MiB)
    {128 * 1024, 128},         // URDFs, small batches (16 MiB)
    {1024 * 1024, 32},         // batches (32 MiB)
    {4 * 1024 * 1024, 8},      // large batches (32 MiB)
    {24 * 1024 * 1024, 4},     // the largest batch: 1000 knots x 3000 outputs (96 MiB)
}};

// Room iceoryx takes inside a chunk payload before ours: its request/response header
// (< 64 bytes) plus alignment padding; generous on purpose.
inline constexpr std::uint32_t kIceoryxOverhead = 256;

// The largest payload (our header + body) a robodiff chunk may have: anything larger is
// refused with RESOURCE_EXHAUSTED before loaning.
constexpr std::uint64_t maxChunkPayload() { return kMempools.back().size - kIceoryxOverhead; }

}  // namespace robodiff::shm
