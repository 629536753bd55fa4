#include "robodiff/codegen/c_emitter.hpp"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "c_entry_points.hpp"
#include "c_prologue.hpp"
#include "compact_addressing.hpp"
#include "lane_pairs.hpp"
#include "lowering.hpp"

namespace robodiff::codegen {
namespace {

using detail::batchEntry;
using detail::CompactAddressing;
using detail::cString;
using detail::descriptorTables;
using detail::kEvalParams;
using detail::Chunk;
using detail::Instr;
using detail::InstrKind;
using detail::LoweredFunction;
using detail::Operand;
using detail::ZeroRun;
using symbolic::Op;

// Concatenation by appending (GCC 12 warns falsely, -Wrestrict, on "literal" + string&&).
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::string s;
  (s += ... += parts);
  return s;
}

// Single-knot functions below this many operations whose sin-cos kernels all take
// inputs check those inputs' range once, at entry, instead of in every kernel call; a
// second, cold copy of the body (per-call checks) serves arguments beyond the range.
// Measured (docs/code-generation.md): the frame Jacobians of the Panda and Talos
// free-flyer (131-175 operations) ran 7-8% faster; the Panda's CRBA and RNEA (502, 973)
// 0-3% slower, and their compilation took 30-45% longer.
constexpr std::uint32_t kEntryRangeCheckBelow = 256;

// Scalar: one knot, `double` locals. Vector: RD_W knots in the lanes of `rd_v` locals.
enum class Flavour { Scalar, Vector };

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

// Prints one chunk of a lowered function as the body of a C function.
class ChunkPrinter {
 public:
  // Output blocks of at least this many values are claimed by the batched chunk.
  static constexpr std::uint32_t kClaimMinimum = 256;

  ChunkPrinter(const FunctionDefinition& f, Flavour flavour) : f_(f), flavour_(flavour) {}

  // true: sin and cos by the _in_range kernels, with no range check of their own (the
  // function checks its arguments at entry).
  void inRangeKernels(bool on) { in_range_ = on; }

  // `signature` is the function's declaration up to, not including, the body.
  // `first`: the function's first chunk, where the batched flavour claims its outputs.
  // `compact`: not empty, the body is addressed compactly (compact_addressing.hpp): its
  // constants in the table `compact`_k, the body itself in the function `compact`_body.
  std::string print(const std::string& signature, const Chunk& chunk, bool first = false,
                    const std::string& compact = "") {
    if (compact.empty()) return printOnce(signature, chunk, first, "");
    CompactAddressing addressing;
    compact_ = &addressing;
    printOnce(signature, chunk, first, compact);  // counts the accesses
    addressing.plan();
    std::string text = addressing.table(compact + "_k") + printOnce(signature, chunk, first, compact);
    compact_ = nullptr;
    return text;
  }

 private:
  std::string printOnce(const std::string& signature, const Chunk& chunk, bool first, const std::string& compact) {
    out_.str("");
    declared_.assign(chunk.slots, 0);
    declared_pair_.assign(chunk.pair_slots, 0);
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
    for (const Instr& ins : chunk.code) printInstr(ins, chunk);
    out_ << "}\n";
    return out_.str();
  }

  // A compactly addressed body: a function `compact`_body taking the arrays and the base
  // pointers as restrict parameters, called by `signature`.
  void printCompactBody(const std::string& signature, const Chunk& chunk, const std::string& compact,
                        const std::set<std::uint32_t>& in_blocks, const std::set<std::uint32_t>& out_blocks,
                        bool uses_work) {
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

  bool vector() const { return flavour_ == Flavour::Vector; }
  const char* kernelSuffix() const { return in_range_ ? "_in_range" : ""; }
  static std::string localName(std::uint32_t slot) {
    return cat("t", std::to_string(slot));
  }
  const char* type() const { return vector() ? "rd_v" : "double"; }

  // An array's element, its address, a constant: through the compact addressing, if any.
  std::string element(const std::string& array, std::uint32_t index) const {
    return compact_ ? compact_->element(array, index) : cat(array, "[", std::to_string(index), "]");
  }
  std::string address(const std::string& array, std::uint32_t index, std::uint32_t width) const {
    return compact_ ? compact_->address(array, index, width) : cat(array, " + ", std::to_string(index));
  }
  std::string literal(double value) const {
    const std::string text = cDoubleLiteral(value);
    return compact_ ? compact_->constant(text) : text;
  }

  // "rd_pair p3 = " the first time a pair local is assigned, "p3 = " after.
  std::string assignPair(std::uint32_t slot) {
    std::string lhs = cat("p", std::to_string(slot), " = ");
    if (declared_pair_[slot]) return lhs;
    declared_pair_[slot] = 1;
    return "rd_pair " + lhs;
  }

  // "double t3 = " the first time a local is assigned in this function, "t3 = " after.
  std::string assign(std::uint32_t slot) {
    std::string lhs = localName(slot) + " = ";
    if (declared_[slot]) return lhs;
    declared_[slot] = 1;
    return std::string(type()) + " " + lhs;
  }

  // An operand as a C expression. `helper_argument`: it is passed to a lane-wise helper,
  // so a constant must become a vector.
  std::string operand(const Operand& o, bool helper_argument = false) const {
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

  // An operand of + or - as its magnitude and whether it is negated, so that the sign
  // folds into the operator (a - b, not a + -b).
  std::pair<std::string, bool> signedOperand(const Operand& o) const {
    if (o.kind == Operand::Kind::Constant)
      return {vector() ? cDoubleLiteral(std::fabs(o.value)) : literal(std::fabs(o.value)), std::signbit(o.value)};
    Operand m = o;
    m.negated = false;
    return {operand(m), o.negated};
  }

  std::string expression(const Instr& ins) const {
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

  // Structural zeros of a single knot's block up to this many are stored four at a time
  // (below); more are cleared with one memset of the block.
  // A memset costs ~35 ns before anything else runs (gcc inlines `rep stos`), so it only
  // pays for large blocks: Solo-12's frame Jacobian (63 zeros) 77 -> 38 ns, Talos's (170)
  // 37 -> 25 ns, Talos's M(q) (744 zeros) 530 ns with the memset, 570 ns without.
  static constexpr std::uint32_t kStoredZerosMaximum = 256;

  void printZeros(std::uint32_t block, const std::vector<ZeroRun>& runs) {
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
    std::uint32_t cleared_to = 0;  // elements below this are cleared
    for (const ZeroRun& r : runs)
      for (std::uint32_t k = std::max(r.start, cleared_to); k < r.start + r.length; k = std::max(k + 1, cleared_to)) {
        const std::uint32_t group = k / 4 * 4;
        if (group + 4 <= size) {
          out_ << "  RD_ZERO4(" << address(o, group, 4) << ");\n";
          cleared_to = group + 4;
        } else {
          out_ << "  " << element(o, k) << " = 0.0;\n";
        }
      }
  }

  void printInstr(const Instr& ins, const Chunk& chunk) {
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
        out_ << "  rd_sincos_pair" << kernelSuffix() << "(" << operand(ins.args[0]) << ", &p" << ins.dst << ", &p"
             << ins.dst2 << ");\n";
        break;
      case InstrKind::SinCosQuad:
        for (std::uint32_t slot : {ins.dst, ins.dst2, ins.dst3, ins.dst4}) {
          if (declared_pair_[slot]) continue;
          declared_pair_[slot] = 1;
          out_ << "  rd_pair p" << slot << ";\n";
        }
        out_ << "  rd_sincos_quad" << kernelSuffix() << "(" << operand(ins.args[0]) << ", " << operand(ins.args[1])
             << ", &p" << ins.dst << ", &p" << ins.dst2 << ", &p" << ins.dst3 << ", &p" << ins.dst4 << ");\n";
        break;
      case InstrKind::SinCos:
        for (std::uint32_t slot : {ins.dst, ins.dst2}) {
          if (declared_[slot]) continue;
          declared_[slot] = 1;
          out_ << "  " << type() << " t" << slot << ";\n";
        }
        out_ << "  " << (vector() ? "rd_sincos(" : cat("rd_sincos1", kernelSuffix(), "(")) << operand(ins.args[0])
             << ", &t" << ins.dst << ", &t" << ins.dst2 << ");\n";
        break;
      case InstrKind::StoreOutput:
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

  const FunctionDefinition& f_;
  Flavour flavour_;
  bool in_range_ = false;
  std::ostringstream out_;
  std::vector<char> declared_, declared_pair_;
  CompactAddressing* compact_ = nullptr;  // during print() of a compactly addressed body
};

// A function lowered for C: without lane pairs (the batched code, and compilers without
// vector types) and with them, cut into the same parts; and whether it is addressed
// compactly.
struct Lowerings {
  LoweredFunction plain, paired;
  bool compact = false;
};

// Compactly addressed functions with fewer than this share of their operations in lane
// pairs are cut into parts of half the split threshold: with the parts' transfers short,
// smaller parts spill less. Where pairs are many, smaller parts would cut them apart.
// Measured (direct calls, ns; 1,000 against 500 operations a part): Panda RNEA + J 1,122
// -> 1,024, ABA + J 1,358 -> 1,309; Talos RNEA + J (16% paired) 4,827 -> 4,665, ABA + J
// (13%) 7,450 -> 7,235; free-flying Talos ABA + J (none, output order) 19,769 -> 18,238;
// but Talos ABA value (42% paired) 831 -> 969.
constexpr double kSparselyPairedShare = 0.2;

Lowerings lowerForC(const symbolic::Graph& graph, const FunctionDefinition& f, const CodegenOptions& options) {
  detail::LoweringOptions lo;
  lo.split_threshold = options.split_threshold;
  lo.reuse_slots = options.reuse_temporaries;
  lo.output_order_from = options.output_order_from;
  detail::LanePairMemo memo;
  lo.ready_first_sums = detail::readyFirstSums(graph, f, &memo);
  lo.lane_pair_memo = &memo;
  Lowerings l;
  auto lowerBoth = [&] {
    lo.lane_pairs = options.lane_pairs ? detail::LanePairMode::Order : detail::LanePairMode::Off;
    l.plain = detail::lower(graph, f, lo);
    l.paired = LoweredFunction{};
    if (!options.lane_pairs) return;
    lo.lane_pairs = detail::LanePairMode::Emit;
    l.paired = detail::lower(graph, f, lo);
    if (l.paired.chunks.size() != l.plain.chunks.size() || l.paired.transfer_slots != l.plain.transfer_slots)
      throw std::logic_error("c_emitter: the lowering with lane pairs changed the parts");
  };
  lowerBoth();
  const bool any_pairs = l.paired.lane_pairs > 0 || l.paired.sincos_lane_pairs > 0;
  const std::uint64_t instructions =
      any_pairs ? std::uint64_t{l.paired.operations} - l.paired.lane_pairs : l.plain.operations;
  l.compact = options.compact_addressing_from > 0 && instructions >= options.compact_addressing_from;
  if (l.compact && l.plain.chunks.size() > 1 && l.paired.lane_pairs < kSparselyPairedShare * l.plain.operations) {
    lo.split_threshold = options.split_threshold / 2;
    lowerBoth();
  }
  return l;
}

}  // namespace

std::string cDoubleLiteral(double value) {
  if (std::isnan(value)) return "NAN";
  if (std::isinf(value)) return value > 0 ? "INFINITY" : "-INFINITY";
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value);  // shortest form that reads back exactly
  std::string s(buf, end);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

std::uint64_t singleKnotInstructions(const symbolic::Graph& graph, const FunctionDefinition& function,
                                     const CodegenOptions& options) {
  function.validate(graph);
  detail::LoweringOptions lo;
  lo.split_threshold = options.split_threshold;
  lo.output_order_from = options.output_order_from;
  lo.lane_pairs = options.lane_pairs ? detail::LanePairMode::Emit : detail::LanePairMode::Off;
  detail::LanePairMemo memo;
  lo.ready_first_sums = detail::readyFirstSums(graph, function, &memo);
  lo.lane_pair_memo = &memo;
  const LoweredFunction lowered = detail::lower(graph, function, lo);
  return std::uint64_t{lowered.operations} - lowered.lane_pairs;
}

std::uint64_t compactAddressingFrom(std::uint64_t instruction_cache_bytes) {
  if (instruction_cache_bytes == 0) return kCompactAddressingFrom;
  return static_cast<std::uint64_t>(static_cast<double>(instruction_cache_bytes) / kCodeBytesPerInstruction);
}

std::uint64_t hostInstructionCacheBytes() {
  const long bytes = sysconf(_SC_LEVEL1_ICACHE_SIZE);
  return bytes > 0 ? static_cast<std::uint64_t>(bytes) : 0;
}

GeneratedLibrary generateLibrary(const symbolic::Graph& graph, const std::vector<FunctionDefinition>& functions,
                                 const CodegenOptions& options) {
  if (functions.empty()) throw std::invalid_argument("generateLibrary: no functions");
  const std::uint32_t w = options.batch_width;
  if (w > 16 || (w & (w - 1)) != 0)
    throw std::invalid_argument("generateLibrary: batch_width must be 0 (by target), 1, 2, 4, 8 or 16");
  std::set<std::string> names;
  for (const auto& f : functions) {
    f.validate(graph);
    if (!names.insert(f.name).second) throw std::invalid_argument("generateLibrary: two functions named '" + f.name + "'");
  }
  const std::string head = detail::prologue(options);
  GeneratedLibrary lib;
  lib.headers.push_back({"robodiff/codegen/abi.h", abiHeaderText()});
  lib.headers.push_back({"robodiff/codegen/sincos_kernel.h", sincosKernelText()});
  std::ostringstream main;
  main << head;
  std::ostringstream table;
  table << "static const robodiff_function_desc rd_functions[] = {\n";

  for (const auto& f : functions) {
    const Lowerings lowerings = lowerForC(graph, f, options);
    const LoweredFunction& lowered = lowerings.plain;
    const LoweredFunction& paired = lowerings.paired;
    const bool compact = lowerings.compact;
    const std::string prefix = "rd_" + f.name;
    const std::uint32_t parts = static_cast<std::uint32_t>(lowered.chunks.size());

    GeneratedFunctionInfo info;
    info.name = f.name;
    info.needed_nodes = lowered.needed_nodes;
    info.operations = lowered.operations;
    info.sincos_pairs = lowered.sincos_pairs;
    info.parts = parts;
    info.transfer_slots = lowered.transfer_slots;
    info.lane_pairs = paired.lane_pairs;
    for (const Chunk& c : lowered.chunks) info.max_locals = std::max(info.max_locals, c.slots);
    lib.functions.push_back(info);

    ChunkPrinter scalar(f, Flavour::Scalar), vector(f, Flavour::Vector);
    // The single-knot code of part p: with lane pairs (and sin-cos pairs) where the
    // compiler has vector types.
    const bool any_pairs = paired.lane_pairs > 0 || paired.sincos_lane_pairs > 0;
    auto scalarPart = [&](const std::string& signature, std::uint32_t p) {
      const std::string table = compact ? prefix + (parts > 1 ? "_p" + std::to_string(p) : "") : "";
      if (!any_pairs) return scalar.print(signature, lowered.chunks[p], false, table);
      return "#if RD_PAIRS\n" + scalar.print(signature, paired.chunks[p], false, table) + "#else\n" +
             scalar.print(signature, lowered.chunks[p], false, table) + "#endif\n";
    };
    const bool batched = w != 1;  // else RD_VECTOR is 0: no SIMD code to write or compile
    main << "/* ---- " << f.name << ": " << lowered.operations << " operations, " << parts << " part(s) ---- */\n\n";
    const bool checked_at_entry = parts == 1 && !compact && any_pairs && !lowered.sincos_inputs.empty() &&
                                  lowered.operations < kEntryRangeCheckBelow;
    if (checked_at_entry) {
      ChunkPrinter in_range(f, Flavour::Scalar);
      in_range.inRangeKernels(true);
      main << "#if RD_PAIRS\n"
           << in_range.print("RD_SCALAR_FN static inline RD_ALWAYS_INLINE void " + prefix + "_in_range" + kEvalParams,
                             paired.chunks[0])
           << scalar.print("RD_SCALAR_FN RD_COLD static void " + prefix + "_exact" + kEvalParams, lowered.chunks[0])
           << detail::rangeCheckedEntry(prefix, lowered.sincos_inputs) << "#else\n"
           << scalar.print("RD_SCALAR_FN static void " + prefix + "_eval" + kEvalParams, lowered.chunks[0])
           << "#endif\n\n";
    } else if (parts == 1) {
      main << scalarPart("RD_SCALAR_FN static void " + prefix + "_eval" + kEvalParams, 0) << "\n";
    }
    if (parts == 1) {
      if (batched)
        main << "#if RD_VECTOR\n" << vector.print("static void " + prefix + "_chunk" + kEvalParams, lowered.chunks[0], true)
             << "#endif\n\n";
    } else {
      for (std::uint32_t p = 0; p < parts; ++p) {
        const std::string part = prefix + "_p" + std::to_string(p);
        std::ostringstream file;
        file << head << "RD_HIDDEN void " << part << kEvalParams << ";\n"
             << scalarPart("RD_SCALAR_FN RD_SCALAR_PART RD_HIDDEN void " + part + kEvalParams, p)
             << "\n";
        if (batched)
          file << "#if RD_VECTOR\nRD_HIDDEN void " << part << "_v" << kEvalParams << ";\n"
               << vector.print("RD_HIDDEN void " + part + "_v" + kEvalParams, lowered.chunks[p], p == 0) << "#endif\n";
        lib.sources.push_back({f.name + "_part" + std::to_string(p) + ".c", file.str()});
        main << "RD_HIDDEN void " << part << kEvalParams << ";\n";
        if (batched) main << "#if RD_VECTOR\nRD_HIDDEN void " << part << "_v" << kEvalParams << ";\n#endif\n";
      }
      main << "\nstatic void " << prefix << "_eval" << kEvalParams << " {\n";
      for (std::uint32_t p = 0; p < parts; ++p) main << "  " << prefix << "_p" << p << "(in, out, w);\n";
      main << "}\n\n";
      if (batched) {
        main << "#if RD_VECTOR\nstatic void " << prefix << "_chunk" << kEvalParams << " {\n";
        for (std::uint32_t p = 0; p < parts; ++p) main << "  " << prefix << "_p" << p << "_v(in, out, w);\n";
        main << "}\n#endif\n\n";
      }
    }
    main << batchEntry(f, prefix, lowered.transfer_slots) << descriptorTables(f, prefix);

    const std::uint64_t t = lowered.transfer_slots;
    const std::uint64_t staged = static_cast<std::uint64_t>(f.inputCount()) + f.outputCount();
    table << "  {" << cString(f.name) << ", " << f.inputs.size() << "u, " << (f.inputs.empty() ? "NULL" : prefix + "_inputs")
          << ", " << f.outputs.size() << "u, " << prefix << "_outputs, " << t << "u, "
          << "RD_VECTOR ? (uint64_t)RD_W * " << (t + staged) << "u : " << t << "u, RD_W, " << prefix << "_eval, "
          << prefix << "_eval_batch},\n";
  }
  table << "};\n\n"
        << "RD_EXPORT const robodiff_library_desc robodiff_library = {\n"
        << "  ROBODIFF_ABI_VERSION, (uint32_t)sizeof(robodiff_library_desc), " << cString(kGeneratorVersion) << ", "
        << functions.size() << "u, rd_functions};\n";
  main << table.str();
  lib.sources.insert(lib.sources.begin(), SourceFile{"library.c", main.str()});
  return lib;
}

}  // namespace robodiff::codegen
