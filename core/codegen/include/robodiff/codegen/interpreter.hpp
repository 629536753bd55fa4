// The interpreter: a function evaluated the moment it is traced, before (or instead
// of) compiling it. The graph is lowered exactly as for the C code (only the needed
// nodes, negations folded, sin/cos paired, slots reused by liveness) into a compact
// instruction array. That array is then scheduled (any order respecting the data flow:
// results stay bit-identical) so that instructions of one opcode come together, slots
// reassigned by liveness in that order, and run as groups: one dispatch, then a tight
// loop over the group's independent entries (Panda RNEA Jacobian: 6787 instructions in
// 264 groups), instead of one mispredicted indirect jump per instruction.
//
// Same conventions as a compiled function (abi.h): one pointer per input and output
// block, a caller-provided work buffer of workSize() doubles, no allocation, const and
// thread-safe with one work buffer per thread.
#pragma once

#include <cstdint>
#include <vector>

#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen {

class Interpreter {
 public:
  // Throws std::invalid_argument when the definition does not validate against graph.
  Interpreter(const symbolic::Graph& graph, FunctionDefinition function);

  const FunctionDefinition& definition() const { return function_; }
  std::size_t workSize() const { return work_size_; }  // doubles, for evaluate and evaluateBatch
  std::size_t instructionCount() const { return code_.size() - 1; }  // End not counted

  void evaluate(const double* const* in, double* const* out, double* work) const;
  // n knots; knot k of block b at in[b] + k * size (as abi.h's eval_batch).
  void evaluateBatch(std::uint64_t n, const double* const* in, double* const* out, double* work) const;

  enum class Code : std::uint8_t {
    Load, Store, StoreNeg, Zero, Neg,
    Sin, Cos, SinCos, Tan, Asin, Acos, Atan, Exp, Log, Sqrt, Tanh, Abs,
    Add, Sub, Mul, Div, Atan2, Pow, Min, Max, Select,
    MulAdd, MulSub, SubMul,  // a*b + c, a*b - c, c - a*b (rounded twice, as unfused)
    MulMul, AddAdd, AddSub, SubAdd,  // (a*b)*c, (a+b)+c, (a+b)-c, c-(a+b)
    End,                     // the last instruction
  };
  // Load: v[dst] = in[a][b]; Store(Neg): out[a][b] = (-)v[c]; Zero: out[a][..] = 0; SinCos: v[dst] = sin(v[a]),
  // v[b] = cos(v[a]); otherwise v[dst] = op(v[a], v[b], v[c]).
  struct Instruction {
    Code code;
    std::uint32_t dst, a, b, c;
  };
  // The instructions as lowered and assembled (End last), before scheduling.
  const std::vector<Instruction>& code() const { return code_; }
  // Dispatches per evaluation: runs of one opcode after scheduling (End not counted).
  std::size_t groupCount() const { return groups_; }
  // Instructions per evaluation after fusing single-use products and sums (End not counted).
  std::size_t executedCount() const { return executed_; }
  static const char* name(Code code);  // "MulAdd"

 private:
  void run(std::uint64_t knot, const double* const* in, double* const* out, double* v) const;
  template <class Field>
  void runStream(const Field* stream, std::uint64_t knot, const double* const* in, double* const* out,
                 double* v) const;

  FunctionDefinition function_;
  std::vector<std::uint32_t> input_sizes_, output_sizes_;
  std::vector<double> constants_;  // copied to v[0 ..) at the start of each evaluation
  std::vector<Instruction> code_;
  // What run() executes: groups [code, n, n entries of operandsOf(code) slot numbers]
  // ..., then End. Each group is one dispatch and a tight loop over its entries.
  // Held in stream16_ instead when every number in it fits in 16 bits.
  std::vector<std::uint32_t> stream_;
  std::vector<std::uint16_t> stream16_;
  std::size_t groups_ = 0;
  std::size_t executed_ = 0;
  std::size_t work_size_ = 0;
};

}  // namespace robodiff::codegen
