// Graphs, definitions and helpers shared by the code generation tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/graph.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen::testing {

using robodiff::testing::TempDir;
using symbolic::Graph;
using symbolic::Op;

// A random graph using every Op with arguments kept in safe ranges (inputs in [-1, 1]),
// negations and constants sprinkled in, some sin/cos of one argument; a dense and a
// sparse output block, plus constant, input and negated-input outputs.
FunctionDefinition randomFunction(Graph& g, const std::string& name, std::uint32_t seed, int operations);

// Forward kinematics of a planar-ish chain of n revolute joints with offsets: products
// of rotations by sin/cos of each angle (3x3 rotation and position outputs).
FunctionDefinition chainFunction(Graph& g, const std::string& name, int joints);

// A Jacobian-like sparse lower-triangular block (n x n) next to a dense vector.
FunctionDefinition triangularFunction(Graph& g, const std::string& name, int n);

// A dense n x n block that is mostly structural zeros, in runs of many lengths (a band
// and scattered entries), one of them -0.0.
FunctionDefinition bandedFunction(Graph& g, const std::string& name, int n);

// Links of each limb of twoLimbsFunction.
inline constexpr std::uint32_t kLimbLinks = 12;

// One limb: a recursion over its links, each reading the previous link's two values and
// two inputs, as a forward kinematics pass does: c' = c x_i - s y_i, s' = s x_i + c y_i,
// e = e + c' / (1 + s' s'). A `skewed` limb starts from c = c0 c0: one operation more,
// everything after it one level deeper than in its twin.
std::vector<NodeId> limbValues(Graph& g, std::uint32_t first_input, bool skewed = false);

// Two limbs, their values interleaved in one block: [e_0 left, e_0 right, e_1 left, ...],
// in one column, or (cols 2) the left limb's in column 0 and the right limb's in column 1.
// Every operation has its twin: C computes them in lane pairs.
FunctionDefinition twoLimbsFunction(Graph& g, std::uint32_t cols = 1);

// The ops reachable from a definition's outputs.
std::vector<bool> opsUsed(const Graph& g, const FunctionDefinition& f);

// Inputs: `knots` points, uniform in [-1, 1], laid out knot by knot per block.
std::vector<std::vector<double>> randomInputs(const FunctionDefinition& f, std::uint64_t knots, std::uint32_t seed);
// Output blocks for `knots` points, filled with NaN: an entry a function fails to write shows.
std::vector<std::vector<double>> outputBuffers(const FunctionDefinition& f, std::uint64_t knots);

// Pointers to each block, offset to knot `knot`.
std::vector<const double*> pointers(const std::vector<std::vector<double>>& blocks, const FunctionDefinition& f,
                                    std::uint64_t knot = 0, bool inputs = true);
std::vector<double*> pointers(std::vector<std::vector<double>>& blocks, const FunctionDefinition& f,
                              std::uint64_t knot = 0);

// Graph::evaluate's outputs of knot `knot` of `inputs`, per block.
std::vector<std::vector<double>> reference(const Graph& g, const FunctionDefinition& f,
                                           const std::vector<std::vector<double>>& inputs, std::uint64_t knot);

// |a - b| <= tolerance * max(|a|, |b|) (both NaN counts as equal).
bool closeRelative(double a, double b, double tolerance = 1e-12);

// Compiles `lib` (into a temporary folder), evaluates its function `f` single-knot at
// three random points and expects every output element within `tolerance` of the
// graph's (the outputs start as NaN, so an element left unwritten fails).
void expectCompiledAsTheGraph(const Graph& g, const FunctionDefinition& f, const GeneratedLibrary& lib,
                              double tolerance);

}  // namespace robodiff::codegen::testing

namespace robodiff::codegen::testing {

// Whether `program` is found in PATH (compilers other than cc are optional).
bool haveProgram(const std::string& program);

// The number of times `needle` occurs in `text`.
std::size_t countOf(const std::string& text, const std::string& needle);

// Whether /proc/cpuinfo lists the CPU flag `flag` ("avx512f", "fma").
bool cpuHasFlag(const std::string& flag);

// The disassembly of function `symbol` in `library` (objdump -d); empty when it is not there.
std::string disassembly(const std::filesystem::path& library, const std::string& symbol);

// The shared libraries `library` names as needed (readelf -d; binutils come with gcc).
std::vector<std::string> neededLibraries(const std::filesystem::path& library);

// y = sin(x) as function "f": its code calls libm's sincos beyond the sin-cos kernel's
// range (|x| > 2^19).
GeneratedLibrary sinLibrary(Graph& g);

// Function "f" of the compiled library `library` (one input, one output) at x.
double evaluateAt(const std::filesystem::path& library, double x);

// The default options with `compiler` as the compiler.
CompilerOptions withCompiler(const std::string& compiler);

// sinLibrary built in a fresh directory with `options` by each of `compilers` that is
// installed (a message for each that is not); `check` gets the compiler and the report.
void forEachInstalledCompiler(const std::vector<std::string>& compilers, CompilerOptions options,
                              const std::function<void(const std::string&, const CompileReport&)>& check);

}  // namespace robodiff::codegen::testing
