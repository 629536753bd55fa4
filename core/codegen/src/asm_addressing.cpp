#include "asm_addressing.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <vector>

namespace robodiff::codegen::detail {
namespace {

constexpr char kFrame = 'F', kPool = 'K';

std::string token(char base, int offset) { return "@" + std::string(1, base) + std::to_string(offset) + "@"; }

// Each token in the text: its base and offset, in order, with where it starts and ends.
template <class Visit>
void forEachToken(const std::string& text, Visit visit) {
  for (std::size_t at = text.find('@'); at != std::string::npos; at = text.find('@', at)) {
    const std::size_t end = text.find('@', at + 1);
    if (end == std::string::npos) throw std::logic_error("asm: an unterminated operand token");
    visit(text[at + 1], std::stoi(text.substr(at + 2, end - at - 2)), at, end + 1);
    at = end + 1;
  }
}

// How one instruction reads an operand: a VEX encoding takes a one-byte displacement in
// [-128, 127]; an EVEX one (a register above 15, or an EVEX-only form) scales it by the
// operand's size: a multiple of 8 (scalars, 64-bit loads) or 16 (128-bit operands)
// within 127 of them.
struct Read {
  bool evex = false;
  int size = 16;
};

Read readOf(const std::string& line) {
  Read r;
  for (int reg = 16; reg < 32 && !r.evex; ++reg) r.evex = line.find("mm" + std::to_string(reg)) != std::string::npos;
  const std::string mnemonic = line.substr(0, line.find_first_of("\t ", 1));
  if (mnemonic.ends_with("q")) r.evex = true;  // vpandq, vpxorq
  const bool scalar = mnemonic.ends_with("sd") || mnemonic.ends_with("hpd") || mnemonic.ends_with("ddup");
  r.size = scalar ? 8 : 16;
  return r;
}

bool shortDisplacement(int d, const Read& r) {
  if (!r.evex) return d >= -128 && d <= 127;
  return d % r.size == 0 && d / r.size >= -128 && d / r.size <= 127;
}

// The bias whose operands' displacements take the fewest bytes (reads: offset, how
// it is read -> count). Candidates: the biases that put an offset read at either end of
// a one-byte range, or in its middle.
int bestBias(const std::map<std::pair<int, std::pair<bool, int>>, int>& reads) {
  std::vector<int> candidates;
  for (const auto& [read, count] : reads)
    for (int shift : {128, -127, 0, 1016, -1016, 2032, -2032}) candidates.push_back(read.first + shift);
  int best = candidates.front();
  long best_bytes = -1;
  for (int bias : candidates) {
    long bytes = 0;
    for (const auto& [read, count] : reads)
      bytes += static_cast<long>(count) * (shortDisplacement(read.first - bias, {read.second.first, read.second.second}) ? 1 : 4);
    if (best_bytes < 0 || bytes < best_bytes) {
      best_bytes = bytes;
      best = bias;
    }
  }
  return best;
}

}  // namespace

std::string frameOperand(int offset) { return token(kFrame, offset); }
std::string poolOperand(int offset) { return token(kPool, offset); }

BaseBiases chooseBiases(const std::string& text) {
  std::map<std::pair<int, std::pair<bool, int>>, int> frame, pool;
  forEachToken(text, [&](char base, int offset, std::size_t start, std::size_t) {
    const std::size_t line = text.rfind('\n', start) == std::string::npos ? 0 : text.rfind('\n', start) + 1;
    const Read r = readOf(text.substr(line, text.find('\n', start) - line));
    ++(base == kFrame ? frame : pool)[{offset, {r.evex, r.size}}];
  });
  BaseBiases b;
  if (!frame.empty()) b.frame = bestBias(frame);
  if (!pool.empty()) b.pool = bestBias(pool);
  return b;
}

std::string resolveOperands(const std::string& text, const BaseBiases& biases) {
  std::string out;
  out.reserve(text.size());
  std::size_t copied = 0;
  forEachToken(text, [&](char base, int offset, std::size_t start, std::size_t end) {
    const bool frame = base == kFrame;
    const std::optional<int>& bias = frame ? biases.frame : biases.pool;
    out.append(text, copied, start - copied);
    if (!bias) out += frame ? std::to_string(offset) + "(%rsp)" : ".LRDc0+" + std::to_string(offset) + "(%rip)";
    else out += std::to_string(offset - *bias) + (frame ? "(%rbp)" : "(%rbx)");
    copied = end;
  });
  out.append(text, copied, std::string::npos);
  return out;
}

}  // namespace robodiff::codegen::detail
