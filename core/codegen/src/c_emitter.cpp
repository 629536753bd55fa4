#include "robodiff/codegen/c_emitter.hpp"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "asm_emitter.hpp"
#include "c_entry_points.hpp"
#include "c_prologue.hpp"
#include "chunk_printer.hpp"
#include "compact_addressing.hpp"
#include "entry_kernels.hpp"
#include "lane_pairs.hpp"
#include "lowering.hpp"

namespace robodiff::codegen {
namespace {

using detail::batchEntry;
using detail::cString;
using detail::descriptorTables;
using detail::kEvalParams;
using detail::Chunk;
using detail::ChunkPrinter;
using detail::Flavour;
using detail::LoweredFunction;

// Single-knot functions below this many operations whose sin-cos kernels all take
// inputs check those inputs' range once, at entry, instead of in every kernel call.
// Where every operation waits on a kernel, the kernels are computed at entry and the
// body compiled once (entry_kernels.hpp); elsewhere a second, cold copy of the body
// (per-call checks) serves arguments beyond the range. Measured (docs/code-generation.md):
// the frame Jacobians of the Panda and Talos free-flyer (131-175 operations) ran 7-8%
// faster with the copy; the Panda's CRBA and RNEA (502, 973) 0-3% slower, and their
// compilation took 30-45% longer.
constexpr std::uint32_t kEntryRangeCheckBelow = 256;

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

Lowerings lowerForC(const symbolic::Graph& graph, const FunctionDefinition& f, const CodegenOptions& options,
                    detail::FunctionPairing& pairing) {
  detail::LoweringOptions lo;
  lo.split_threshold = options.split_threshold;
  lo.reuse_slots = options.reuse_temporaries;
  lo.output_order_from = options.output_order_from;
  lo.ready_first_sums = pairing.ready_first_sums;
  lo.lane_pair_memo = &pairing.memo;
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

namespace {

// What the build report says of a lowered function.
GeneratedFunctionInfo functionInfo(const FunctionDefinition& f, const Lowerings& l) {
  GeneratedFunctionInfo info;
  info.name = f.name;
  info.needed_nodes = l.plain.needed_nodes;
  info.operations = l.plain.operations;
  info.sincos_pairs = l.plain.sincos_pairs;
  info.parts = static_cast<std::uint32_t>(l.plain.chunks.size());
  info.transfer_slots = l.plain.transfer_slots;
  info.lane_pairs = l.paired.lane_pairs;
  for (const Chunk& c : l.plain.chunks) info.max_locals = std::max(info.max_locals, c.slots);
  return info;
}

// The C names of a function's pieces start with this (rd_<name>_eval, rd_<name>_p0, ...).
std::string prefixOf(const FunctionDefinition& f) { return "rd_" + f.name; }

bool anyPairs(const Lowerings& l) { return l.paired.lane_pairs > 0 || l.paired.sincos_lane_pairs > 0; }

// The single-knot code of part p: with lane pairs (and sin-cos pairs) where the compiler
// has vector types.
std::string scalarPart(const FunctionDefinition& f, const Lowerings& l, const std::string& signature, std::uint32_t p) {
  const std::uint32_t parts = static_cast<std::uint32_t>(l.plain.chunks.size());
  const std::string table = l.compact ? prefixOf(f) + (parts > 1 ? "_p" + std::to_string(p) : "") : "";
  ChunkPrinter scalar(f, Flavour::Scalar);
  scalar.packOutputGroups(parts == 1);
  if (!anyPairs(l)) return scalar.print(signature, l.plain.chunks[p], false, table);
  return "#if RD_PAIRS\n" + scalar.print(signature, l.paired.chunks[p], false, table) + "#else\n" +
         scalar.print(signature, l.plain.chunks[p], false, table) + "#endif\n";
}

// The single-knot entry point of a function whose kernels all run at its entry
// (entry_kernels.hpp): one body; compilers without vector types check in every call.
void emitKernelsAtEntry(const FunctionDefinition& f, const Lowerings& l, const std::vector<detail::EntryKernel>& kernels,
                        std::ostream& main) {
  ChunkPrinter scalar(f, Flavour::Scalar), at_entry(f, Flavour::Scalar);
  at_entry.kernelsAtEntry(kernels, l.plain.sincos_inputs);
  scalar.packOutputGroups(true);
  at_entry.packOutputGroups(true);
  const std::string signature = "RD_SCALAR_FN static void " + prefixOf(f) + "_eval" + kEvalParams;
  main << "#if RD_PAIRS\n"
       << at_entry.print(signature, l.paired.chunks[0]) << "#else\n"
       << scalar.print(signature, l.plain.chunks[0]) << "#endif\n\n";
}

// The single-knot entry point of a function whose kernels' arguments are checked at its
// entry: the body with unchecked kernels, inlined, and a cold copy with per-call checks.
void emitColdCopy(const FunctionDefinition& f, const Lowerings& l, std::ostream& main) {
  const std::string prefix = prefixOf(f);
  ChunkPrinter scalar(f, Flavour::Scalar), in_range(f, Flavour::Scalar);
  in_range.inRangeKernels(true);
  scalar.packOutputGroups(true);
  in_range.packOutputGroups(true);
  main << "#if RD_PAIRS\n"
       << in_range.print("RD_SCALAR_FN static inline RD_ALWAYS_INLINE void " + prefix + "_in_range" + kEvalParams,
                         l.paired.chunks[0])
       << scalar.print("RD_SCALAR_FN RD_COLD static void " + prefix + "_exact" + kEvalParams, l.plain.chunks[0])
       << detail::rangeCheckedEntry(prefix, l.plain.sincos_inputs) << "#else\n"
       << scalar.print("RD_SCALAR_FN static void " + prefix + "_eval" + kEvalParams, l.plain.chunks[0])
       << "#endif\n\n";
}

// A function in one part, in library.c: its single-knot entry point, with the kernels'
// range checked at entry where that pays (the kernels at entry, or a cold exact copy
// beside the body), and its batched chunk.
void emitWhole(const FunctionDefinition& f, const Lowerings& l, bool batched, std::ostream& main) {
  const LoweredFunction& lowered = l.plain;
  const bool checked_at_entry = !l.compact && anyPairs(l) && !lowered.sincos_inputs.empty() &&
                                lowered.operations < kEntryRangeCheckBelow;
  const auto kernels = checked_at_entry ? detail::entryKernels(l.paired.chunks[0]) : std::nullopt;
  if (kernels)
    emitKernelsAtEntry(f, l, *kernels, main);
  else if (checked_at_entry)
    emitColdCopy(f, l, main);
  else
    main << scalarPart(f, l, "RD_SCALAR_FN static void " + prefixOf(f) + "_eval" + kEvalParams, 0) << "\n";
  if (batched) {
    ChunkPrinter vector(f, Flavour::Vector);
    main << "#if RD_VECTOR\n" << vector.print("static void " + prefixOf(f) + "_chunk" + kEvalParams, lowered.chunks[0], true)
         << "#endif\n\n";
  }
}

// A split function: each part in a file of its own (`head` first), declared in library.c
// and called there in order by the function's entry points.
void emitParts(const FunctionDefinition& f, const Lowerings& l, bool batched, const std::string& head,
               GeneratedLibrary& lib, std::ostream& main) {
  const std::string prefix = prefixOf(f);
  const std::uint32_t parts = static_cast<std::uint32_t>(l.plain.chunks.size());
  ChunkPrinter vector(f, Flavour::Vector);
  for (std::uint32_t p = 0; p < parts; ++p) {
    const std::string part = prefix + "_p" + std::to_string(p);
    std::ostringstream file;
    file << head << "RD_HIDDEN void " << part << kEvalParams << ";\n"
         << scalarPart(f, l, "RD_SCALAR_FN RD_SCALAR_PART RD_HIDDEN void " + part + kEvalParams, p) << "\n";
    if (batched)
      file << "#if RD_VECTOR\nRD_HIDDEN void " << part << "_v" << kEvalParams << ";\n"
           << vector.print("RD_HIDDEN void " + part + "_v" + kEvalParams, l.plain.chunks[p], p == 0) << "#endif\n";
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

// The function's row of the library's descriptor table.
std::string descriptorRow(const FunctionDefinition& f, const LoweredFunction& lowered) {
  const std::string prefix = prefixOf(f);
  const std::uint64_t t = lowered.transfer_slots;
  const std::uint64_t staged = static_cast<std::uint64_t>(f.inputCount()) + f.outputCount();
  std::ostringstream row;
  row << "  {" << cString(f.name) << ", " << f.inputs.size() << "u, " << (f.inputs.empty() ? "NULL" : prefix + "_inputs")
      << ", " << f.outputs.size() << "u, " << prefix << "_outputs, " << t << "u, "
      << "RD_VECTOR ? (uint64_t)RD_W * " << (t + staged) << "u : " << t << "u, RD_W, " << prefix << "_eval, " << prefix
      << "_eval_batch},\n";
  return row.str();
}

}  // namespace

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
  std::vector<detail::FunctionPairing> pairings;
  for (const auto& f : functions) pairings.push_back(detail::pairingOf(graph, f));
  if (options.assembly && w == 1)
    if (auto target = detail::hostAsmTarget())
      if (auto lib = detail::generateAssemblyLibrary(graph, functions, options, *target, &pairings)) return *lib;
  const std::string head = detail::prologue(options);
  const bool batched = w != 1;  // else RD_VECTOR is 0: no SIMD code to write or compile
  GeneratedLibrary lib;
  lib.headers.push_back({"robodiff/codegen/abi.h", abiHeaderText()});
  lib.headers.push_back({"robodiff/codegen/sincos_kernel.h", sincosKernelText()});
  std::ostringstream main;
  main << head;
  std::ostringstream table;
  table << "static const robodiff_function_desc rd_functions[] = {\n";
  for (std::size_t i = 0; i < functions.size(); ++i) {
    const FunctionDefinition& f = functions[i];
    const Lowerings l = lowerForC(graph, f, options, pairings[i]);
    lib.functions.push_back(functionInfo(f, l));
    const std::size_t parts = l.plain.chunks.size();
    main << "/* ---- " << f.name << ": " << l.plain.operations << " operations, " << parts << " part(s) ---- */\n\n";
    if (parts == 1) emitWhole(f, l, batched, main);
    else emitParts(f, l, batched, head, lib, main);
    main << batchEntry(f, prefixOf(f), l.plain.transfer_slots) << descriptorTables(f, prefixOf(f));
    table << descriptorRow(f, l.plain);
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
