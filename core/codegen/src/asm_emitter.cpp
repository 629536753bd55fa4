#include "asm_emitter.hpp"

#include <cstddef>
#include <sstream>

#include "asm_program.hpp"
#include "asm_schedule.hpp"
#include "lane_pairs.hpp"
#include "lowering.hpp"
#include "robodiff/codegen/abi.h"

namespace robodiff::codegen::detail {
namespace {

// One record of the descriptor tables: fields at their C offsets (abi.h), padding between.
class Record {
 public:
  Record(std::ostream& out, std::size_t size) : out_(out), size_(size) {}
  ~Record() { pad(size_); }
  void quad(std::size_t offset, const std::string& value) { field(offset, 8, "\t.quad\t" + value); }
  void word(std::size_t offset, std::uint64_t value) { field(offset, 4, "\t.long\t" + std::to_string(value)); }

 private:
  void field(std::size_t offset, std::size_t bytes, const std::string& line) {
    pad(offset);
    out_ << line << "\n";
    at_ = offset + bytes;
  }
  void pad(std::size_t to) {
    if (to > at_) out_ << "\t.zero\t" << to - at_ << "\n";
    at_ = std::max(at_, to);
  }
  std::ostream& out_;
  std::size_t size_, at_ = 0;
};

// Strings as bytes (any name is safe), each with a local label.
class Strings {
 public:
  std::string label(const std::string& s) {
    const std::string l = ".LRDs" + std::to_string(count_++);
    text_ << l << ":\n\t.byte\t";
    for (unsigned char c : s) text_ << static_cast<int>(c) << ",";
    text_ << "0\n";
    return l;
  }
  std::string print() const { return "\t.section\t.rodata\n" + text_.str(); }

 private:
  std::ostringstream text_;
  int count_ = 0;
};

// eval_batch(n, in, out, work): eval on knot k's slices of the caller's arrays, k < n.
std::string batchLoop(const FunctionDefinition& f, const std::string& prefix) {
  const std::size_t ni = f.inputs.size(), no = f.outputs.size();
  const std::size_t pointers = (8 * (ni + no) + 15) / 16 * 16;  // after five pushes: aligned calls
  std::ostringstream s;
  const std::string sym = prefix + "_eval_batch";
  s << "\t.text\n\t.p2align 4\n\t.type\t" << sym << ", @function\n" << sym << ":\n"
    << "\tpush\t%rbx\n\tpush\t%rbp\n\tpush\t%r12\n\tpush\t%r13\n\tpush\t%r14\n"
    << "\tsub\t$" << pointers << ", %rsp\n"
    << "\tmov\t%rdi, %rbx\n\tmov\t%rsi, %rbp\n\tmov\t%rdx, %r12\n\tmov\t%rcx, %r13\n\txor\t%r14d, %r14d\n"
    << ".LRD" << prefix << "_loop:\n\tcmp\t%rbx, %r14\n\tjae\t.LRD" << prefix << "_done\n";
  auto point = [&](const char* base, std::size_t b, std::uint64_t size, std::size_t slot) {
    s << "\tmov\t" << 8 * b << "(" << base << "), %rax\n\timul\t$" << 8 * size << ", %r14, %rcx\n"
      << "\tadd\t%rcx, %rax\n\tmov\t%rax, " << 8 * slot << "(%rsp)\n";
  };
  for (std::size_t b = 0; b < ni; ++b) point("%rbp", b, f.inputs[b].size, b);
  for (std::size_t b = 0; b < no; ++b) point("%r12", b, f.outputs[b].size(), ni + b);
  s << "\tlea\t0(%rsp), %rdi\n\tlea\t" << 8 * ni << "(%rsp), %rsi\n\tmov\t%r13, %rdx\n"
    << "\tcall\t" << prefix << "_eval\n\tinc\t%r14\n\tjmp\t.LRD" << prefix << "_loop\n"
    << ".LRD" << prefix << "_done:\n\tadd\t$" << pointers << ", %rsp\n"
    << "\tpop\t%r14\n\tpop\t%r13\n\tpop\t%r12\n\tpop\t%rbp\n\tpop\t%rbx\n\tret\n"
    << "\t.size\t" << sym << ", .-" << sym << "\n\n";
  return s.str();
}

// The function's input and output tables (abi.h's layouts).
void descriptorTables(const FunctionDefinition& f, const std::string& prefix, Strings& strings, std::ostream& data) {
  if (!f.inputs.empty()) {
    data << "\t.p2align 3\n" << prefix << "_inputs:\n";
    for (const InputBlock& b : f.inputs) {
      Record r(data, sizeof(robodiff_input_desc));
      r.quad(offsetof(robodiff_input_desc, name), strings.label(b.name));
      r.word(offsetof(robodiff_input_desc, size), b.size);
    }
  }
  for (std::size_t j = 0; j < f.outputs.size(); ++j) {
    const OutputBlock& b = f.outputs[j];
    if (b.kind != OutputKind::Sparse) continue;
    auto list = [&](const char* what, const std::vector<std::uint32_t>& v) {
      if (v.empty()) return;
      data << prefix << "_o" << j << "_" << what << ":\n";
      for (std::uint32_t x : v) data << "\t.long\t" << x << "\n";
    };
    data << "\t.p2align 3\n";
    list("row_ptr", b.row_ptr);
    data << "\t.p2align 3\n";
    list("col_idx", b.col_idx);
  }
  data << "\t.p2align 3\n" << prefix << "_outputs:\n";
  for (std::size_t j = 0; j < f.outputs.size(); ++j) {
    const OutputBlock& b = f.outputs[j];
    const bool sparse = b.kind == OutputKind::Sparse;
    const std::string o = prefix + "_o" + std::to_string(j);
    Record r(data, sizeof(robodiff_output_desc));
    r.quad(offsetof(robodiff_output_desc, name), strings.label(b.name));
    r.word(offsetof(robodiff_output_desc, rows), b.rows);
    r.word(offsetof(robodiff_output_desc, cols), b.cols);
    r.word(offsetof(robodiff_output_desc, kind), sparse ? ROBODIFF_OUTPUT_SPARSE : ROBODIFF_OUTPUT_DENSE);
    r.word(offsetof(robodiff_output_desc, nnz), b.size());
    r.quad(offsetof(robodiff_output_desc, row_ptr), sparse ? o + "_row_ptr" : "0");
    r.quad(offsetof(robodiff_output_desc, col_idx), sparse && !b.col_idx.empty() ? o + "_col_idx" : "0");
  }
}

void functionRow(const FunctionDefinition& f, const std::string& prefix, Strings& strings, std::ostream& data) {
  Record r(data, sizeof(robodiff_function_desc));
  r.quad(offsetof(robodiff_function_desc, name), strings.label(f.name));
  r.word(offsetof(robodiff_function_desc, n_inputs), f.inputs.size());
  r.quad(offsetof(robodiff_function_desc, inputs), f.inputs.empty() ? "0" : prefix + "_inputs");
  r.word(offsetof(robodiff_function_desc, n_outputs), f.outputs.size());
  r.quad(offsetof(robodiff_function_desc, outputs), prefix + "_outputs");
  r.quad(offsetof(robodiff_function_desc, work_size), "0");
  r.quad(offsetof(robodiff_function_desc, batch_work_size), "0");
  r.word(offsetof(robodiff_function_desc, batch_width), 1);
  r.quad(offsetof(robodiff_function_desc, eval), prefix + "_eval");
  r.quad(offsetof(robodiff_function_desc, eval_batch), prefix + "_eval_batch");
}

// The function in one part, with the C's lane pairs where it computes any (readyFirstSums
// is false then), each sin-cos on its own (the entry kernels take four lanes); nullopt
// where the function is large.
std::optional<LoweredFunction> lowerWhole(const symbolic::Graph& graph, const FunctionDefinition& f,
                                          const CodegenOptions& options, FunctionPairing& pairing) {
  LoweringOptions lo;
  lo.split_threshold = 0;
  lo.reuse_slots = options.reuse_temporaries;
  lo.output_order_from = options.output_order_from;
  lo.ready_first_sums = pairing.ready_first_sums;
  lo.lane_pair_memo = &pairing.memo;
  if (options.lane_pairs && !lo.ready_first_sums) lo.lane_pairs = LanePairMode::Emit;
  lo.sincos_lanes = false;
  LoweredFunction lowered = lower(graph, f, lo);
  const std::uint32_t instructions = lowered.operations - lowered.lane_pairs;
  if (instructions >= kAssemblyBelow || lowered.chunks.size() != 1) return std::nullopt;
  return lowered;
}

}  // namespace

std::optional<AsmTarget> hostAsmTarget() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return std::nullopt;
  AsmTarget t;
  t.xmm_registers = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") ? 32 : 16;
  return t;
#else
  return std::nullopt;
#endif
}

std::optional<GeneratedLibrary> generateAssemblyLibrary(const symbolic::Graph& graph,
                                                        const std::vector<FunctionDefinition>& functions,
                                                        const CodegenOptions& options, const AsmTarget& target,
                                                        std::vector<FunctionPairing>* pairings) {
  std::vector<FunctionPairing> found;
  if (!pairings) {
    for (const FunctionDefinition& f : functions) found.push_back(pairingOf(graph, f));
    pairings = &found;
  }
  GeneratedLibrary lib;
  AsmConstants constants;
  Strings strings;
  std::ostringstream code, data;
  data << "\t.section\t.data.rel.ro,\"aw\"\n\t.p2align 3\n";
  std::ostringstream rows;
  for (std::size_t i = 0; i < functions.size(); ++i) {
    const FunctionDefinition& f = functions[i];
    const std::optional<LoweredFunction> whole = lowerWhole(graph, f, options, (*pairings)[i]);
    if (!whole) return std::nullopt;
    const LoweredFunction& lowered = *whole;
    std::optional<AsmProgram> program = buildAsmProgram(lowered.chunks[0], f);
    if (!program || !asmBlockRegistersSuffice(*program)) return std::nullopt;
    scheduleForLatency(*program);
    const std::string prefix = "rd_" + f.name;
    code << "/* " << f.name << ": " << lowered.operations << " operations */\n"
         << printAsmFunction(*program, prefix + "_eval", target, constants) << batchLoop(f, prefix);
    descriptorTables(f, prefix, strings, data);
    functionRow(f, prefix, strings, rows);
    GeneratedFunctionInfo info;
    info.name = f.name;
    info.needed_nodes = lowered.needed_nodes;
    info.operations = lowered.operations;
    info.sincos_pairs = lowered.sincos_pairs;
    info.lane_pairs = lowered.lane_pairs;
    info.max_locals = lowered.chunks[0].slots;
    lib.functions.push_back(info);
  }
  std::ostringstream s;
  s << "/* Generated by " << kGeneratorVersion << " (x86-64 assembly, " << target.xmm_registers
    << " registers). Do not edit. */\n"
    << code.str() << data.str() << "\t.p2align 3\n.LRDfunctions:\n" << rows.str();
  {
    s << "\t.globl\trobodiff_library\n\t.type\trobodiff_library, @object\n\t.size\trobodiff_library, "
      << sizeof(robodiff_library_desc) << "\n\t.p2align 3\nrobodiff_library:\n";
    Record r(s, sizeof(robodiff_library_desc));
    r.word(offsetof(robodiff_library_desc, abi_version), ROBODIFF_ABI_VERSION);
    r.word(offsetof(robodiff_library_desc, descriptor_size), sizeof(robodiff_library_desc));
    r.quad(offsetof(robodiff_library_desc, generator_version), strings.label(kGeneratorVersion));
    r.word(offsetof(robodiff_library_desc, n_functions), functions.size());
    r.quad(offsetof(robodiff_library_desc, functions), ".LRDfunctions");
  }
  s << strings.print() << constants.print() << "\t.section\t.note.GNU-stack,\"\",@progbits\n";
  lib.sources.push_back({"library.s", s.str()});
  return lib;
}

}  // namespace robodiff::codegen::detail
