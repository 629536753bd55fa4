#include "chunk_printer.hpp"

#include <cmath>
#include <stdexcept>

#include "robodiff/codegen/c_emitter.hpp"

namespace robodiff::codegen::detail {
namespace {

using symbolic::Op;

const char* functionName(Op op) {
  switch (op) {
    case Op::Sin: return "sin";
    case Op::Cos: return "cos";
    case Op::Tan: return "tan";
    case Op::Asin: return "asin";
    case Op::Acos: return "acos";
    case Op::Atan: return "atan";
    case Op::Exp: return "exp";
    case Op::Log: return "log";
    case Op::Sqrt: return "sqrt";
    case Op::Tanh: return "tanh";
    case Op::Abs: return "fabs";
    case Op::Atan2: return "atan2";
    case Op::Pow: return "pow";
    case Op::Min: return "fmin";
    case Op::Max: return "fmax";
    default: return nullptr;
  }
}

}  // namespace

std::string ChunkPrinter::print(const std::string& signature, const Chunk& chunk, bool first,
                                const std::string& compact) {
  if (compact.empty()) return printOnce(signature, chunk, first, "");
  CompactAddressing addressing;
  compact_ = &addressing;
  printOnce(signature, chunk, first, compact);  // counts the accesses
  addressing.plan();
  std::string text = addressing.table(compact + "_k") + printOnce(signature, chunk, first, compact);
  compact_ = nullptr;
  return text;
}

std::string ChunkPrinter::printOnce(const std::string& signature, const Chunk& chunk, bool first,
                                    const std::string& compact) {
  out_.str("");
  declared_.assign(chunk.slots, 0);
  declared_pair_.assign(chunk.pair_slots, 0);
  groups_ = pack_groups_ && !vector() ? planOutputGroups(f_, chunk, kStoredZerosMaximum) : OutputGroupPlan{};
  std::set<std::uint32_t> in_blocks, out_blocks, zeroed, claimed;
  bool uses_work = false;
  for (const Instr& ins : chunk.code) {
    if (ins.kind == InstrKind::LoadInput) in_blocks.insert(ins.block);
    if (ins.kind == InstrKind::StoreOutput || ins.kind == InstrKind::ZeroOutput) out_blocks.insert(ins.block);
    if (ins.kind == InstrKind::ZeroOutput) zeroed.insert(ins.block);
    if (ins.args[0].kind == Operand::Kind::Input) in_blocks.insert(ins.args[0].block);
    if (ins.kind == InstrKind::LoadTransfer || ins.kind == InstrKind::StoreTransfer ||
        ins.kind == InstrKind::LoadTransferPair || ins.kind == InstrKind::StoreTransferPair)
      uses_work = true;
  }
  if (vector() && first)
    for (std::uint32_t b = 0; b < f_.outputs.size(); ++b)
      if (!zeroed.count(b) && f_.outputs[b].size() >= kClaimMinimum) {
        claimed.insert(b);
        out_blocks.insert(b);
      }
  if (compact_) {
    printCompactBody(signature, chunk, compact, in_blocks, out_blocks, uses_work);
    return out_.str();
  }
  out_ << signature << " {\n";
  for (std::uint32_t b : in_blocks) out_ << "  const double* restrict i" << b << " = in[" << b << "];\n";
  for (std::uint32_t b : out_blocks) out_ << "  double* restrict o" << b << " = out[" << b << "];\n";
  if (in_blocks.empty()) out_ << "  (void)in;\n";
  if (out_blocks.empty()) out_ << "  (void)out;\n";
  if (!uses_work) out_ << "  (void)w;\n";
  // The batched chunk scatters each output value to RD_W knots' arrays, and a scatter
  // to a line not in cache waits for the line to be read first. memset claims a block's
  // lines in bulk (the string store writes whole lines, read from nowhere), so the
  // scatters that follow hit cache. Measured on the free-flying Talos's sparse RNEA
  // Jacobian, 1,986 values a knot: 2.7-3.5 us a knot in a batch of 1,000 without,
  // 1.9-2.1 with. Blocks with structural zeros are cleared anyway (ZeroOutput).
  for (std::uint32_t b : claimed)
    out_ << "  memset(o" << b << ", 0, RD_W * " << f_.outputs[b].size() << " * sizeof(double)); /* claim the lines */\n";
  if (entry_kernels_) printEntryBlock(chunk);
  for (const Instr& ins : chunk.code)
    if (!entry_kernels_ || ins.kind != InstrKind::ZeroOutput) printInstr(ins, chunk);
  out_ << "}\n";
  return out_.str();
}

void ChunkPrinter::printEntryBlock(const Chunk& chunk) {
  entry_unit_.assign(chunk.code.size(), -1);
  std::int64_t unit = 0;
  for (const EntryKernel& k : *entry_kernels_) {
    entry_unit_.at(k.at) = unit;
    unit += static_cast<std::int64_t>(k.units.size());
  }
  const EntryBlock block = entryKernelBlock(*entry_kernels_, *entry_angles_);
  out_ << block.head;
  for (const Instr& ins : chunk.code)
    if (ins.kind == InstrKind::ZeroOutput) printInstr(ins, chunk);
  out_ << block.kernels;
}

bool ChunkPrinter::atEntry(const Instr& ins, const Chunk& chunk) {
  if (entry_unit_.empty()) return false;
  const std::int64_t unit = entry_unit_.at(static_cast<std::size_t>(&ins - chunk.code.data()));
  if (unit < 0) throw std::logic_error("ChunkPrinter: a sin-cos kernel missing from the entry block");
  const auto u = static_cast<std::uint32_t>(unit);
  auto copy = [&](const std::string& local, std::uint32_t v, char what) {
    out_ << "  " << local << " = " << entryUnitName(v, what) << ";\n";
  };
  if (ins.kind == InstrKind::SinCos) {
    copy(localName(ins.dst), u, 's');
    copy(localName(ins.dst2), u, 'c');
    return true;
  }
  const std::string p = "p";
  copy(p + std::to_string(ins.dst), u, 's');
  copy(p + std::to_string(ins.dst2), u, 'c');
  if (ins.kind == InstrKind::SinCosQuad) {
    copy(p + std::to_string(ins.dst3), u + 1, 's');
    copy(p + std::to_string(ins.dst4), u + 1, 'c');
  }
  return true;
}

void ChunkPrinter::printCompactBody(const std::string& signature, const Chunk& chunk, const std::string& compact,
                                    const std::set<std::uint32_t>& in_blocks,
                                    const std::set<std::uint32_t>& out_blocks, bool uses_work) {
  std::vector<std::string> parameters, arguments;
  for (std::uint32_t b : in_blocks) {
    parameters.push_back("const double* restrict i" + std::to_string(b));
    arguments.push_back("in[" + std::to_string(b) + "]");
  }
  for (std::uint32_t b : out_blocks) {
    parameters.push_back("double* restrict o" + std::to_string(b));
    arguments.push_back("out[" + std::to_string(b) + "]");
  }
  if (uses_work) {
    parameters.push_back("double* restrict w");
    arguments.push_back("w");
  }
  for (const std::string& p : compact_->parameters()) parameters.push_back(p);
  for (const std::string& a : compact_->arguments(compact + "_k")) arguments.push_back(a);
  auto list = [](const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
    return s.empty() ? std::string("void") : s;
  };
  out_ << "RD_NOIPA RD_SCALAR_FN RD_SCALAR_PART RD_HIDDEN void " << compact << "_body(" << list(parameters) << ");\n"
       << "RD_NOIPA RD_SCALAR_FN RD_SCALAR_PART RD_HIDDEN void " << compact << "_body(" << list(parameters) << ") {\n";
  for (const Instr& ins : chunk.code) printInstr(ins, chunk);
  out_ << "}\n"
       << signature << " {\n"
       << "  (void)in;\n  (void)out;\n  (void)w;\n"
       << "  " << compact << "_body(" << (arguments.empty() ? "" : list(arguments)) << ");\n"
       << "}\n";
}

std::string ChunkPrinter::literal(double value) const {
  const std::string text = cDoubleLiteral(value);
  return compact_ ? compact_->constant(text) : text;
}

std::string ChunkPrinter::assignPair(std::uint32_t slot) {
  std::string lhs = cat("p", std::to_string(slot), " = ");
  if (declared_pair_[slot]) return lhs;
  declared_pair_[slot] = 1;
  return "rd_pair " + lhs;
}

std::string ChunkPrinter::assign(std::uint32_t slot) {
  std::string lhs = localName(slot) + " = ";
  if (declared_[slot]) return lhs;
  declared_[slot] = 1;
  return std::string(type()) + " " + lhs;
}

std::string ChunkPrinter::operand(const Operand& o, bool helper_argument) const {
  switch (o.kind) {
    case Operand::Kind::Slot:
      return cat(o.negated ? "-" : "", localName(o.slot));
    case Operand::Kind::Lane:
      return cat(o.negated ? "-" : "", "p", std::to_string(o.slot), "[", std::to_string(o.lane), "]");
    case Operand::Kind::Pair:
      return cat(o.negated ? "-" : "", "p", std::to_string(o.slot));
    case Operand::Kind::Constant: {
      if (vector()) return helper_argument ? "rd_splat(" + cDoubleLiteral(o.value) + ")" : cDoubleLiteral(o.value);
      return literal(o.value);
    }
    case Operand::Kind::Input: {
      const char* sign = o.negated ? "-" : "";
      if (vector())
        return cat(sign, "rd_gather(i", std::to_string(o.block), " + ", std::to_string(o.index), ", ",
                   std::to_string(f_.inputs[o.block].size), ")");
      return sign + element("i" + std::to_string(o.block), o.index);
    }
  }
  return {};
}

std::pair<std::string, bool> ChunkPrinter::signedOperand(const Operand& o) const {
  if (o.kind == Operand::Kind::Constant)
    return {vector() ? cDoubleLiteral(std::fabs(o.value)) : literal(std::fabs(o.value)), std::signbit(o.value)};
  Operand m = o;
  m.negated = false;
  return {operand(m), o.negated};
}

std::string ChunkPrinter::expression(const Instr& ins) const {
  const Operand* a = ins.args;
  switch (ins.op) {
    case Op::Add: {
      auto [x, nx] = signedOperand(a[0]);
      auto [y, ny] = signedOperand(a[1]);
      if (!nx && !ny) return x + " + " + y;
      if (!nx && ny) return x + " - " + y;
      if (nx && !ny) return y + " - " + x;
      return "-" + x + " - " + y;
    }
    case Op::Sub: {
      auto [x, nx] = signedOperand(a[0]);
      auto [y, ny] = signedOperand(a[1]);
      if (!nx && !ny) return x + " - " + y;
      if (!nx && ny) return x + " + " + y;
      if (nx && !ny) return "-" + x + " - " + y;
      return y + " - " + x;
    }
    case Op::Mul: return operand(a[0]) + " * " + operand(a[1]);
    case Op::Div: return operand(a[0]) + " / " + operand(a[1]);
    case Op::Neg: return "-(" + operand(a[0]) + ")";
    case Op::SelectPositive:
      if (vector()) return "rd_select(" + operand(a[0], true) + ", " + operand(a[1], true) + ", " + operand(a[2], true) + ")";
      return operand(a[0]) + " > 0.0 ? " + operand(a[1]) + " : " + operand(a[2]);
    default: break;
  }
  const char* fn = functionName(ins.op);
  if (!fn) throw std::logic_error(std::string("c_emitter: cannot print ") + symbolic::toString(ins.op));
  std::string call = vector() ? std::string("rd_") + fn + "(" : std::string(fn) + "(";
  call += operand(a[0], true);
  if (symbolic::arity(ins.op) == 2) call += ", " + operand(a[1], true);
  return call + ")";
}

void ChunkPrinter::printZeros(std::uint32_t block, const std::vector<ZeroRun>& runs) {
  std::uint32_t zeros = 0;
  for (const ZeroRun& r : runs) zeros += r.length;
  if (zeros > kStoredZerosMaximum) {
    const std::uint32_t size = f_.outputs[block].size();
    if (compact_) compact_->whole("o" + std::to_string(block), size);
    out_ << "  memset(o" << block << ", 0, " << size << " * sizeof(double));\n";
    return;
  }
  // Four at a time from elements 4k of the block (into a 32-byte aligned output these
  // stores are aligned: none is split across two cache lines or two pages). A group of
  // four with any zero is cleared whole: the block's other stores come after this, so
  // they overwrite the rest, and a frame Jacobian's scattered zeros take fewer stores.
  const std::string o = "o" + std::to_string(block);
  const std::uint32_t size = f_.outputs[block].size();
  forEachZeroStore(
      runs, size,
      [&](std::uint32_t group) {  // a group stored whole with its values is not cleared first
        if (!groups_.packs(block, group)) out_ << "  RD_ZERO4(" << address(o, group, 4) << ");\n";
      },
      [&](std::uint32_t k) { out_ << "  " << element(o, k) << " = 0.0;\n"; });
}

void ChunkPrinter::printGroupedStore(const Instr& ins, std::uint32_t at) {
  auto name = [&](std::uint32_t element) { return cat("rd_o", std::to_string(ins.block), "_", std::to_string(element)); };
  out_ << "  const double " << name(ins.index) << " = " << operand(ins.args[0]) << ";\n";
  const OutputGroup& g = groups_.groups[groups_.group_of[at]];
  if (g.last != at) return;
  out_ << "  RD_STORE4(" << address("o" + std::to_string(g.block), g.start, 4);
  for (std::uint32_t e = 0; e < 4; ++e) out_ << ", " << (g.store[e] == kZeroElement ? "0.0" : name(g.start + e));
  out_ << ");\n";
}

void ChunkPrinter::printInstr(const Instr& ins, const Chunk& chunk) {
  switch (ins.kind) {
    case InstrKind::LoadInput:
      out_ << "  " << assign(ins.dst);
      if (vector())
        out_ << "rd_gather(i" << ins.block << " + " << ins.index << ", " << f_.inputs[ins.block].size << ");\n";
      else
        out_ << element("i" + std::to_string(ins.block), ins.index) << ";\n";
      break;
    case InstrKind::LoadTransfer:
      out_ << "  " << assign(ins.dst);
      if (vector()) out_ << "rd_loadu(w + " << ins.index << " * RD_W);\n";
      else out_ << element("w", ins.index) << ";\n";
      break;
    case InstrKind::Compute:
      out_ << "  " << assign(ins.dst) << expression(ins) << ";\n";
      break;
    case InstrKind::PackPair:
      out_ << "  " << assignPair(ins.dst) << "(rd_pair){" << operand(ins.args[0]) << ", " << operand(ins.args[1])
           << "};\n";
      break;
    case InstrKind::ComputePair:
      out_ << "  " << assignPair(ins.dst) << expression(ins) << ";\n";
      break;
    case InstrKind::LoadTransferPair:
      out_ << "  " << assignPair(ins.dst) << "rd_load_pair(" << address("w", ins.index, 2) << ");\n";
      break;
    case InstrKind::StoreTransferPair:
      out_ << "  rd_store_pair(" << address("w", ins.index, 2) << ", " << operand(ins.args[0]) << ");\n";
      break;
    case InstrKind::SinCosPair:
      for (std::uint32_t slot : {ins.dst, ins.dst2}) {
        if (declared_pair_[slot]) continue;
        declared_pair_[slot] = 1;
        out_ << "  rd_pair p" << slot << ";\n";
      }
      if (atEntry(ins, chunk)) break;
      out_ << "  rd_sincos_pair" << kernelSuffix() << "(" << operand(ins.args[0]) << ", &p" << ins.dst << ", &p"
           << ins.dst2 << ");\n";
      break;
    case InstrKind::SinCosQuad:
      for (std::uint32_t slot : {ins.dst, ins.dst2, ins.dst3, ins.dst4}) {
        if (declared_pair_[slot]) continue;
        declared_pair_[slot] = 1;
        out_ << "  rd_pair p" << slot << ";\n";
      }
      if (atEntry(ins, chunk)) break;
      out_ << "  rd_sincos_quad" << kernelSuffix() << "(" << operand(ins.args[0]) << ", " << operand(ins.args[1])
           << ", &p" << ins.dst << ", &p" << ins.dst2 << ", &p" << ins.dst3 << ", &p" << ins.dst4 << ");\n";
      break;
    case InstrKind::SinCos:
      for (std::uint32_t slot : {ins.dst, ins.dst2}) {
        if (declared_[slot]) continue;
        declared_[slot] = 1;
        out_ << "  " << type() << " t" << slot << ";\n";
      }
      if (atEntry(ins, chunk)) break;
      out_ << "  " << (vector() ? "rd_sincos(" : cat("rd_sincos1", kernelSuffix(), "(")) << operand(ins.args[0])
           << ", &t" << ins.dst << ", &t" << ins.dst2 << ");\n";
      break;
    case InstrKind::StoreOutput:
      if (!groups_.group_of.empty()) {
        const auto at = static_cast<std::uint32_t>(&ins - chunk.code.data());
        if (groups_.group_of[at] != kNoGroup) {
          printGroupedStore(ins, at);
          break;
        }
      }
      if (vector())
        out_ << "  rd_scatter(o" << ins.block << " + " << ins.index << ", " << f_.outputs[ins.block].size() << ", "
             << operand(ins.args[0], true) << ");\n";
      else
        out_ << "  " << element("o" + std::to_string(ins.block), ins.index) << " = " << operand(ins.args[0]) << ";\n";
      break;
    case InstrKind::ZeroOutput:
      if (vector())  // the chunk's RD_W knots are consecutive
        out_ << "  memset(o" << ins.block << ", 0, RD_W * " << f_.outputs[ins.block].size() << " * sizeof(double));\n";
      else
        printZeros(ins.block, chunk.zero_runs.at(ins.index));
      break;
    case InstrKind::StoreTransfer:
      if (vector()) out_ << "  rd_storeu(w + " << ins.index << " * RD_W, " << operand(ins.args[0]) << ");\n";
      else out_ << "  " << element("w", ins.index) << " = " << operand(ins.args[0]) << ";\n";
      break;
  }
}

}  // namespace robodiff::codegen::detail
