#include "asm_registers.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "asm_addressing.hpp"
#include "asm_entry_kernels.hpp"

namespace robodiff::codegen::detail {

namespace {

constexpr const char* kBlockRegisters[] = {"%rax", "%rcx", "%rdx", "%r8", "%r9", "%r10", "%r11"};
constexpr int kBlockRegisterCount = 7;
constexpr std::uint32_t kNever = 0xffffffffu;
constexpr int kNoRegister = -1;

// The input and output blocks a program reads or writes, each given a register.
struct BlockRegisters {
  std::map<std::uint32_t, int> input, output;
  int count() const { return static_cast<int>(input.size() + output.size()); }
};

BlockRegisters blockRegisters(const AsmProgram& p) {
  BlockRegisters b;
  for (const ValueHome& h : p.homes)
    if (h.kind == ValueHome::Kind::Input) b.input.emplace(h.block, 0);
  for (const MOp& op : p.ops)
    if (op.code == MCode::Store || op.code == MCode::Store4)
      b.output.emplace(op.block, 0);
  int next = 0;
  for (auto& [block, r] : b.input) r = next++;
  for (auto& [block, r] : b.output) r = next++;
  return b;
}

// A sin-cos region's way back from libm: registers saved, the call, results loaded.
struct ColdPath {
  int label = 0;
  int x = 0, sin = 0, cos = 0;  // registers
  std::vector<int> saved;       // xmm registers live across the region
};

std::string xmm(int r) { return "%xmm" + std::to_string(r); }
std::string ymm(int r) { return "%ymm" + std::to_string(r); }

class FunctionPrinter {
 public:
  FunctionPrinter(const AsmProgram& p, const AsmTarget& target, AsmConstants& constants)
      : p_(p), evex_(target.xmm_registers > 16), constants_(constants), blocks_(blockRegisters(p)) {
    if (blocks_.count() > kBlockRegisterCount)
      throw std::logic_error("asm: more blocks than general-purpose registers");
    const std::uint32_t n = p.values();
    uses_.resize(n);
    for (std::uint32_t i = 0; i < p.ops.size(); ++i)
      for (std::uint32_t v : p.ops[i].src)
        if (v != kNoValue && (uses_[v].empty() || uses_[v].back() != i)) uses_[v].push_back(i);
    cursor_.assign(n, 0);
    reg_.assign(n, kNoRegister);
    slot_.assign(n, -1);
    holds_.assign(target.xmm_registers, kNoValue);
    locked_.assign(target.xmm_registers, false);
  }

  std::string print(const std::string& symbol) {
    label_ = symbol;
    kernel_bytes_ = p_.entry_kernels.empty() ? 0 : entryKernelBytes(p_.entry_kernels.size());
    const std::string kept = keepLastKernelGroup();
    for (std::uint32_t i = 0; i < p_.ops.size(); ++i) printOp(i);
    const std::string body = kept + body_.str();
    const BaseBiases bases = p_.ops.size() >= kBasesFrom ? chooseBiases(body) : BaseBiases{};
    const int pushes = (bases.frame ? 1 : 0) + (bases.pool ? 1 : 0);
    const int frame = frameBytes(pushes);
    std::vector<std::string> block_registers(kBlockRegisters, kBlockRegisters + blocks_.count());
    const EntryKernelCode kernels = printEntryKernels(
        symbol, p_.entry_kernels, [&](std::uint32_t b, std::uint32_t i) { return inputMemory(b, i); }, block_registers,
        EntryKernelFrame{0, gprSave()}, constants_);
    std::ostringstream s;
    s << "\t.text\n\t.p2align 4\n\t.type\t" << symbol << ", @function\n" << symbol << ":\n";
    if (bases.frame) s << "\tpush\t%rbp\n";
    if (bases.pool) s << "\tpush\t%rbx\n";
    if (frame > 0) s << "\tsub\t$" << frame << ", %rsp\n";
    if (bases.frame) s << "\tlea\t" << *bases.frame << "(%rsp), %rbp\n";
    if (bases.pool) s << "\tlea\t.LRDc0+" << *bases.pool << "(%rip), %rbx\n";
    for (const auto& [block, r] : blocks_.input) s << "\tmov\t" << 8 * block << "(%rdi), " << kBlockRegisters[r] << "\n";
    for (const auto& [block, r] : blocks_.output) s << "\tmov\t" << 8 * block << "(%rsi), " << kBlockRegisters[r] << "\n";
    s << kernels.hot << resolveOperands(body, bases);
    if (frame > 0) s << "\tadd\t$" << frame << ", %rsp\n";
    if (bases.pool) s << "\tpop\t%rbx\n";
    if (bases.frame) s << "\tpop\t%rbp\n";
    if (upper_dirty_) s << "\tvzeroupper\n";  // no penalty for the caller's SSE code
    s << "\tret\n";
    for (const ColdPath& c : cold_) s << coldPath(c);
    s << kernels.cold;
    s << "\t.size\t" << symbol << ", .-" << symbol << "\n\n";
    return s.str();
  }

 private:
  // The last kernel group's results, still in %ymm1 (sines) and %ymm2 (cosines), given
  // to their values in registers: lane 0 as it is, the others moved out (lanes 2 and 3
  // before vzeroupper clears the upper halves). The body then need not wait for the
  // frame's store and load. Returns that code, vzeroupper included.
  std::string keepLastKernelGroup() {
    if (p_.entry_kernels.empty()) return {};
    const std::uint32_t group = static_cast<std::uint32_t>((p_.entry_kernels.size() - 1) / 4);
    const std::uint32_t lanes = static_cast<std::uint32_t>(p_.entry_kernels.size()) - 4 * group;
    std::map<std::uint32_t, std::uint32_t> value_at;  // frame offset -> value
    for (std::uint32_t v = 0; v < p_.values(); ++v)
      if (p_.homes[v].kind == ValueHome::Kind::EntryKernel && !uses_[v].empty())
        value_at.emplace(p_.homes[v].index, v);
    std::ostringstream high, low;
    int next = 3;
    for (int result = 0; result < 2; ++result) {
      const int vector = 1 + result;
      for (std::uint32_t lane = 0; lane < lanes; ++lane) {
        auto it = value_at.find(64 * group + 32 * result + 8 * lane);
        if (it == value_at.end()) continue;
        int r = vector;
        if (lane > 0) r = next++;
        if (lane == 1) low << "\tvpermilpd\t$1, " << xmm(vector) << ", " << xmm(r) << "\n";
        if (lane >= 2) high << "\tvextractf128\t$1, " << ymm(vector) << ", " << xmm(r) << "\n";
        if (lane == 3) low << "\tvpermilpd\t$1, " << xmm(r) << ", " << xmm(r) << "\n";
        bind(it->second, r);
      }
    }
    return high.str() + "\tvzeroupper\n" + low.str();
  }

  // ---- values and registers ----
  std::uint32_t nextUse(std::uint32_t v, std::uint32_t after) {
    auto& u = uses_[v];
    std::uint32_t& c = cursor_[v];
    while (c < u.size() && u[c] <= after) ++c;
    return c < u.size() ? u[c] : kNever;
  }
  bool diesAt(std::uint32_t v, std::uint32_t i) const { return !uses_[v].empty() && uses_[v].back() == i; }
  bool hasMemory(std::uint32_t v) const { return slot_[v] >= 0 || p_.homes[v].kind != ValueHome::Kind::None; }
  std::string inputMemory(std::uint32_t block, std::uint32_t index) const {
    return std::to_string(8 * index) + "(" + kBlockRegisters[blocks_.input.at(block)] + ")";
  }
  // `lane`: a spilled pair's lane 1 (8 bytes on).
  std::string memory(std::uint32_t v, int lane = 0) {
    if (slot_[v] >= 0) return frameOperand(kernel_bytes_ + 8 * (slot_[v] + lane));
    if (lane != 0) throw std::logic_error("asm: lane 1 of a value with a home");
    const ValueHome& h = p_.homes[v];
    if (h.kind == ValueHome::Kind::Input) return inputMemory(h.block, h.index);
    if (h.kind == ValueHome::Kind::EntryKernel) return frameOperand(static_cast<int>(h.index));
    if (h.kind == ValueHome::Kind::Constant) return poolOperand(constants_.offset(h.bits, h.bits_high));
    throw std::logic_error("asm: a value neither in a register nor in memory");
  }
  // The value's register, or its memory operand.
  std::string where(std::uint32_t v) {
    if (reg_[v] != kNoRegister) return xmm(reg_[v]);
    return memory(v);
  }

  void emit(const std::string& line) {
    body_ << '\t' << line << '\n';
  }

  int freeRegisters() const {
    int n = 0;
    for (std::uint32_t h : holds_) n += h == kNoValue;
    return n;
  }

  // Frees the register whose value is read again last (a value without memory is
  // stored to a slot first; `clean_only`: only values with memory, which cost no code).
  void evict(std::uint32_t after, bool clean_only = false) {
    int best = kNoRegister;
    std::uint32_t best_use = 0;
    bool best_clean = false;
    for (int r = 0; r < static_cast<int>(holds_.size()); ++r) {
      if (holds_[r] == kNoValue || locked_[r] || p_.wide[holds_[r]] || (clean_only && !hasMemory(holds_[r])))
        continue;
      const std::uint32_t use = nextUse(holds_[r], after);
      const bool clean = hasMemory(holds_[r]);
      if (best == kNoRegister || use > best_use || (use == best_use && clean && !best_clean)) {
        best = r;
        best_use = use;
        best_clean = clean;
      }
    }
    if (best == kNoRegister) throw std::logic_error("asm: every register is locked");
    const std::uint32_t v = holds_[best];
    if (!hasMemory(v)) {
      slot_[v] = newSlot(p_.pair[v]);
      emit((p_.pair[v] ? "vmovapd\t" : "vmovsd\t") + xmm(best) + ", " + memory(v));
    }
    reg_[v] = kNoRegister;
    holds_[best] = kNoValue;
  }

  int takeRegister(std::uint32_t at) {
    for (int pass = 0; pass < 2; ++pass) {
      for (int r = 0; r < static_cast<int>(holds_.size()); ++r)
        if (holds_[r] == kNoValue && !locked_[r]) return r;
      evict(at, in_region_);  // a region stores nothing: its cold path would not
    }
    throw std::logic_error("asm: no register");
  }

  void bind(std::uint32_t v, int r) {
    holds_[r] = v;
    reg_[v] = r;
  }

  // Puts v in a register (read back from its memory) and locks it for this operation.
  int inRegister(std::uint32_t v, std::uint32_t at) {
    if (reg_[v] == kNoRegister) {
      const std::string from = memory(v);
      const int r = takeRegister(at);
      emit((p_.pair[v] ? "vmovupd\t" : "vmovsd\t") + from + ", " + xmm(r));
      bind(v, r);
    }
    locked_[reg_[v]] = true;
    return reg_[v];
  }

  // A stack slot of 8 bytes, or for a pair two at an even slot (16 bytes aligned: the
  // frame's slots start 16-byte aligned).
  int newSlot(bool pair) {
    if (!pair && !free_slots_.empty()) {
      const int s = *free_slots_.begin();
      free_slots_.erase(free_slots_.begin());
      return s;
    }
    if (pair)
      for (int s : free_slots_)
        if (s % 2 == 0 && free_slots_.count(s + 1)) {
          free_slots_.erase(s);
          free_slots_.erase(s + 1);
          return s;
        }
    if (!pair) return slots_++;
    if (slots_ % 2 != 0) free_slots_.insert(slots_++);
    slots_ += 2;
    return slots_ - 2;
  }

  void release(std::uint32_t v) {
    if (reg_[v] != kNoRegister) holds_[reg_[v]] = kNoValue;
    reg_[v] = kNoRegister;
    if (slot_[v] >= 0) free_slots_.insert(slot_[v]);
    if (slot_[v] >= 0 && p_.pair[v]) free_slots_.insert(slot_[v] + 1);
    slot_[v] = -1;
  }

  // After operation i: its dying sources released, locks undone, an unread result freed.
  void finish(const MOp& op, std::uint32_t i) {
    for (std::uint32_t v : op.src)
      if (v != kNoValue && diesAt(v, i) && (reg_[v] != kNoRegister || slot_[v] >= 0)) release(v);
    for (std::uint32_t v : {op.dst, op.dst2})
      if (v != kNoValue && uses_[v].empty()) release(v);
    std::fill(locked_.begin(), locked_.end(), false);
  }

  // A register for the result of operation i, whose sources are read before it is
  // written: a dying source's register may serve.
  int resultRegister(const MOp& op, std::uint32_t i) {
    for (std::uint32_t v : op.src)
      if (v != kNoValue && diesAt(v, i) && reg_[v] != kNoRegister) {
        const int r = reg_[v];
        holds_[r] = kNoValue;
        reg_[v] = kNoRegister;
        return r;
      }
    return takeRegister(i);
  }

  // ---- operations ----
  std::string bitwise(const char* vex, const char* evex) const { return evex_ ? evex : vex; }

  void printOp(std::uint32_t i) {
    const MOp& op = p_.ops[i];
    for (std::uint32_t v : op.src)
      if (v != kNoValue && reg_[v] != kNoRegister) locked_[reg_[v]] = true;
    switch (op.code) {
      case MCode::Add: case MCode::Mul:
        printBinary(op, i, arithmetic(op, op.code == MCode::Add ? "vadd" : "vmul").c_str(), true, false);
        break;
      case MCode::Sub: printBinary(op, i, arithmetic(op, "vsub").c_str(), false, false); break;
      case MCode::Div: printBinary(op, i, arithmetic(op, "vdiv").c_str(), false, false); break;
      case MCode::And: printBinary(op, i, bitwise("vpand", "vpandq").c_str(), true, true); break;
      case MCode::Xor: printBinary(op, i, bitwise("vpxor", "vpxorq").c_str(), true, true); break;
      case MCode::AddQ: printBinary(op, i, "vpaddq", true, true); break;
      case MCode::SubQ: printBinary(op, i, "vpsubq", false, true); break;
      case MCode::ShlQ: {
        const int a = inRegister(op.src[0], i);
        const int d = resultRegister(op, i);
        emit("vpsllq\t$" + std::to_string(op.imm) + ", " + xmm(a) + ", " + xmm(d));
        bind(op.dst, d);
        break;
      }
      case MCode::Sqrt: {
        const int a = inRegister(op.src[0], i);
        const int d = resultRegister(op, i);
        emit("vsqrtsd\t" + xmm(a) + ", " + xmm(a) + ", " + xmm(d));
        bind(op.dst, d);
        break;
      }
      case MCode::Dup: {
        const std::string a = where(op.src[0]);
        const int d = resultRegister(op, i);
        emit("vmovddup\t" + a + ", " + xmm(d));
        bind(op.dst, d);
        break;
      }
      case MCode::High: printHigh(op, i); break;
      case MCode::Fma: printFma(op, i); break;
      case MCode::Pack2: case MCode::Low: case MCode::Pack4: printPack(op, i); break;
      case MCode::Store4:
        emit("vmovupd\t" + ymm(inRegister(op.src[0], i)) + ", " + output(op));
        break;
      case MCode::Store:
        emit("vmovsd\t" + xmm(inRegister(op.src[0], i)) + ", " + output(op));
        break;
      case MCode::KernelBegin: beginRegion(op, i); break;
      case MCode::KernelCheck: {
        const int m = inRegister(op.src[0], i);
        ColdPath c;
        c.label = static_cast<int>(cold_.size());
        c.x = inRegister(op.src[1], i);
        emit("vucomisd\t" + constants_.label(0x4120000000000000ull) + "(%rip), " + xmm(m));
        emit("ja\t.L" + label_ + "_cold" + std::to_string(c.label));
        emit("jp\t.L" + label_ + "_cold" + std::to_string(c.label));
        cold_.push_back(c);
        break;
      }
      case MCode::KernelEnd: {
        ColdPath& c = cold_.back();
        c.sin = reg_[op.src[0]];
        c.cos = reg_[op.src[1]];
        // A value the region read into a register (a constant) leaves it: the cold path
        // did not read it.
        for (int r = 0; r < static_cast<int>(holds_.size()); ++r) {
          const std::uint32_t v = holds_[r];
          if (v == kNoValue || v == op.src[0] || v == op.src[1] || region_start_[r] == v) continue;
          if (!hasMemory(v)) throw std::logic_error("asm: a value computed in a sin-cos region outlives it");
          holds_[r] = kNoValue;
          reg_[v] = kNoRegister;
        }
        for (int r = 0; r < static_cast<int>(holds_.size()); ++r)
          if (holds_[r] != kNoValue && r != c.sin && r != c.cos) c.saved.push_back(r);
        body_ << ".L" << label_ << "_join" << c.label << ":\n";
        in_region_ = false;
        break;
      }
    }
    finish(op, i);
  }

  // The mnemonic of an arithmetic operation: scalar, or packed for a pair's.
  std::string arithmetic(const MOp& op, const char* stem) const {
    return std::string(stem) + (p_.pair[op.dst] ? "pd" : "sd");
  }

  // A pair's lane 1 as a scalar: moved out of its register, or read from its slot.
  void printHigh(const MOp& op, std::uint32_t i) {
    const std::uint32_t a = op.src[0];
    if (reg_[a] == kNoRegister) {
      const std::string from = memory(a, 1);
      const int d = resultRegister(op, i);
      emit("vmovsd\t" + from + ", " + xmm(d));
      return bind(op.dst, d);
    }
    const int ra = inRegister(a, i);
    const int d = resultRegister(op, i);
    emit("vpermilpd\t$1, " + xmm(ra) + ", " + xmm(d));
    bind(op.dst, d);
  }

  std::string output(const MOp& op) const {
    return std::to_string(8 * op.index) + "(" + kBlockRegisters[blocks_.output.at(op.block)] + ")";
  }

  // dst = a op b: a in a register, b where it is (bitwise: a constant's memory only, its
  // 128 bits); commutative operations take the operand in a register first.
  void printBinary(const MOp& op, std::uint32_t i, const char* mnemonic, bool commutative, bool bitwise_op) {
    std::uint32_t a = op.src[0], b = op.src[1];
    auto memoryOk = [&](std::uint32_t v) {
      return !bitwise_op || (reg_[v] == kNoRegister && p_.homes[v].kind == ValueHome::Kind::Constant);
    };
    if (commutative && reg_[a] == kNoRegister && (reg_[b] != kNoRegister || (bitwise_op && !memoryOk(b))))
      std::swap(a, b);
    const int ra = inRegister(a, i);
    if (!memoryOk(b) || (bitwise_op && reg_[b] != kNoRegister)) inRegister(b, i);
    const std::string bt = where(b);
    const int d = resultRegister(op, i);
    emit(std::string(mnemonic) + "\t" + bt + ", " + xmm(ra) + ", " + xmm(d));
    bind(op.dst, d);
  }

  // An output group's elements into one register: two doubles (the upper half zero),
  // or two such halves into 256 bits (EVEX's form where a register is beyond 15).
  void printPack(const MOp& op, std::uint32_t i) {
    const int a = inRegister(op.src[0], i);
    if (op.code == MCode::Pack2 && reg_[op.src[1]] == kNoRegister) {  // lane 1 loaded from memory
      const std::string from = memory(op.src[1]);
      const int d = resultRegister(op, i);
      emit("vmovhpd\t" + from + ", " + xmm(a) + ", " + xmm(d));
      return bind(op.dst, d);
    }
    const int b = op.code == MCode::Low ? kNoRegister : inRegister(op.src[1], i);
    const int d = resultRegister(op, i);
    if (op.code == MCode::Pack2) emit("vunpcklpd\t" + xmm(b) + ", " + xmm(a) + ", " + xmm(d));
    if (op.code == MCode::Low) emit("vmovq\t" + xmm(a) + ", " + xmm(d));
    if (op.code == MCode::Pack4) {
      emit(bitwise("vinsertf128", "vinsertf32x4") + "\t$1, " + xmm(b) + ", " + ymm(a) + ", " + ymm(d));
      upper_dirty_ = true;
    }
    bind(op.dst, d);
  }

  // dst = +-(a * b) +- c in one fused multiply-add, in place where a source dies here.
  void printFma(const MOp& op, std::uint32_t i) {
    std::string name = op.negate_product ? (op.negate_addend ? "vfnmsub" : "vfnmadd")
                                         : (op.negate_addend ? "vfmsub" : "vfmadd");
    const std::string form231 = p_.pair[op.dst] ? "231pd\t" : "231sd\t", form213 = p_.pair[op.dst] ? "213pd\t" : "213sd\t";
    std::uint32_t a = op.src[0], b = op.src[1];
    const std::uint32_t c = op.src[2];
    if (reg_[a] == kNoRegister && reg_[b] != kNoRegister) std::swap(a, b);
    const int ra = inRegister(a, i);
    const bool once = a != c && b != c;  // c read once: its register may take the result
    if (reg_[c] != kNoRegister && diesAt(c, i) && once) {
      const int d = reg_[c];
      emit(name + form231 + where(b) + ", " + xmm(ra) + ", " + xmm(d));
      return moveResult(c, op.dst, d);
    }
    if (diesAt(a, i) && a != c) {
      const int rb = inRegister(b, i);
      emit(name + form213 + where(c) + ", " + xmm(rb) + ", " + xmm(ra));
      return moveResult(a, op.dst, ra);
    }
    if (reg_[b] != kNoRegister && diesAt(b, i) && b != c && b != a) {
      emit(name + form213 + where(c) + ", " + xmm(ra) + ", " + xmm(reg_[b]));
      return moveResult(b, op.dst, reg_[b]);
    }
    const int d = takeRegister(i);
    const std::string from = where(c);
    emit((from[0] == '%' ? "vmovapd\t" : p_.pair[c] ? "vmovupd\t" : "vmovsd\t") + from + ", " + xmm(d));
    emit(name + form231 + where(b) + ", " + xmm(ra) + ", " + xmm(d));
    bind(op.dst, d);
  }
  void moveResult(std::uint32_t dying, std::uint32_t result, int r) {
    reg_[dying] = kNoRegister;
    bind(result, r);
  }

  // Frees the registers the region needs (its most computed values live at once, and
  // three operands read into registers), so that inside it only values with memory are
  // evicted (no code: the cold path leaves the registers as the hot path does).
  void beginRegion(const MOp& op, std::uint32_t i) {
    inRegister(op.src[0], i);
    std::uint32_t end = i + 1;
    while (!(p_.ops[end].code == MCode::KernelEnd && p_.ops[end].imm == static_cast<int>(i))) ++end;
    std::map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> span;  // value -> first, last within
    for (std::uint32_t j = i + 1; j <= end; ++j) {
      const MOp& o = p_.ops[j];
      auto touch = [&](std::uint32_t v) {
        if (v == kNoValue || v == op.src[0] || p_.homes[v].kind != ValueHome::Kind::None) return;
        auto [it, fresh] = span.emplace(v, std::make_pair(j, j));
        it->second.second = std::min(end, std::max(uses_[v].empty() ? j : uses_[v].back(), j));
        (void)fresh;
      };
      for (std::uint32_t v : o.src) touch(v);
      touch(o.dst);
    }
    int need = 0;
    for (std::uint32_t j = i + 1; j <= end; ++j) {
      int live = 0;
      for (const auto& [v, s] : span) live += s.first <= j && j <= s.second;
      need = std::max(need, live + 3);
    }
    while (freeRegisters() < need) evict(i);
    region_start_ = holds_;
    in_region_ = true;
  }

  // The frame: entry kernels' results, spill slots, then the cold paths' save areas.
  int xmmSave() const { return kernel_bytes_ + 8 * slots_; }
  int gprSave() const { return xmmSave() + 16 * static_cast<int>(holds_.size()); }
  int callResults() const { return gprSave() + 8 * kBlockRegisterCount; }

  std::string coldPath(const ColdPath& c) const {
    const int save = xmmSave(), gpr_save = gprSave(), result = callResults();
    std::ostringstream s;
    s << ".L" << label_ << "_cold" << c.label << ":\n\tvzeroupper\n";
    for (int r : c.saved) s << "\tvmovupd\t" << xmm(r) << ", " << save + 16 * r << "(%rsp)\n";
    for (int g = 0; g < blocks_.count(); ++g) s << "\tmov\t" << kBlockRegisters[g] << ", " << gpr_save + 8 * g << "(%rsp)\n";
    if (c.x != 0) s << "\tvmovapd\t" << xmm(c.x) << ", %xmm0\n";
    s << "\tlea\t" << result << "(%rsp), %rdi\n\tlea\t" << result + 8 << "(%rsp), %rsi\n\tcall\tsincos@PLT\n";
    for (int g = 0; g < blocks_.count(); ++g) s << "\tmov\t" << gpr_save + 8 * g << "(%rsp), " << kBlockRegisters[g] << "\n";
    for (int r : c.saved) s << "\tvmovupd\t" << save + 16 * r << "(%rsp), " << xmm(r) << "\n";
    s << "\tvmovsd\t" << result << "(%rsp), " << xmm(c.sin) << "\n\tvmovsd\t" << result + 8 << "(%rsp), " << xmm(c.cos)
      << "\n\tjmp\t.L" << label_ << "_join" << c.label << "\n";
    return s.str();
  }

  // Spill slots, and where there is a cold path its save area; with the return address
  // and the `pushes` bases saved, a multiple of 16, so that the frame is 16-byte aligned
  // (pairs' slots) and calls from the cold paths see an aligned stack.
  int frameBytes(int pushes) const {
    int bytes = xmmSave();
    if (!cold_.empty() || kernel_bytes_ > 0) bytes = callResults() + 16;
    if (bytes == 0) return 0;
    const int saved = 8 + 8 * pushes;
    return (bytes + saved + 15) / 16 * 16 - saved;
  }

  const AsmProgram& p_;
  const bool evex_;
  AsmConstants& constants_;
  const BlockRegisters blocks_;
  std::vector<std::vector<std::uint32_t>> uses_;
  std::vector<std::uint32_t> cursor_;
  std::vector<int> reg_, slot_;
  std::vector<std::uint32_t> holds_;
  std::vector<std::uint32_t> region_start_;  // holds_ as the current sin-cos region began
  std::vector<bool> locked_;
  std::set<int> free_slots_;
  int slots_ = 0;
  int kernel_bytes_ = 0;  // the entry kernels' results, at the frame's start
  bool upper_dirty_ = false;  // a 256-bit register written (vzeroupper before returning)
  std::string label_;     // the function's symbol: its labels start with .L<symbol>
  bool in_region_ = false;
  std::vector<ColdPath> cold_;
  std::ostringstream body_;
};

}  // namespace

bool asmBlockRegistersSuffice(const AsmProgram& program) { return blockRegisters(program).count() <= kBlockRegisterCount; }

std::string printAsmFunction(const AsmProgram& program, const std::string& symbol, const AsmTarget& target,
                             AsmConstants& constants) {
  return FunctionPrinter(program, target, constants).print(symbol);
}

}  // namespace robodiff::codegen::detail
