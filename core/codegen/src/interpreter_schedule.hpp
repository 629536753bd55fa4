// The interpreter's instruction stream. The assembled program is straight-line code whose
// slots are reused by liveness; dispatch (one indirect, often mispredicted jump per
// instruction) dominates its time. Any order that respects the data flow computes every
// value with the same operations on the same operands, so results are bit-identical. This
// step picks one that puts instructions of one opcode together, fuses single-use products
// and sums into their reader, reassigns slots by liveness in the new order, and writes the
// stream the interpreter runs: per group, its opcode, its count, then each entry's fields
// (writes, reads, then block and index). docs/code-generation.md explains the choices.
#pragma once

#include <cstdint>
#include <vector>

#include "robodiff/codegen/interpreter.hpp"

namespace robodiff::codegen::detail {

struct ScheduledStream {
  std::vector<std::uint32_t> stream;  // ends with End and a zero count
  std::size_t groups = 0;             // runs of one opcode (End not counted)
  std::size_t executed = 0;           // instructions after fusion (End not counted)
  std::uint32_t work_size = 0;        // slots used: constants first, then values
};

// `code` as assembled: constants in slots 0 .. nconst-1 (read, never written), `nslots`
// slots in all; no End instruction.
ScheduledStream scheduleInstructions(const std::vector<Interpreter::Instruction>& code, std::uint32_t nconst,
                                     std::uint32_t nslots);

}  // namespace robodiff::codegen::detail
