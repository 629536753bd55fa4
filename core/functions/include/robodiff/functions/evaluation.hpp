// Convenience for callers that are not in a hot loop (CLI, checks, tests): evaluate a
// built function's compiled or interpreted form on Eigen vectors, and read an output
// block back as a dense matrix. Allocates; controllers call the evaluators directly.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/codegen/function_definition.hpp"

namespace robodiff {

// Evaluates `f` (a codegen::Interpreter or codegen::CompiledFunction: evaluate(in, out,
// work) and workSize()) at the runtime inputs, one vector per input block of `def`.
// Returns each output block's doubles. Throws std::invalid_argument on a size mismatch,
// naming the block.
template <class Evaluator>
std::vector<Eigen::VectorXd> evaluateBlocks(const Evaluator& f, const codegen::FunctionDefinition& def,
                                            const std::vector<Eigen::VectorXd>& inputs) {
  if (inputs.size() != def.inputs.size())
    throw std::invalid_argument(def.name + " takes " + std::to_string(def.inputs.size()) + " input blocks, " +
                                std::to_string(inputs.size()) + " given");
  std::vector<const double*> in;
  for (std::size_t b = 0; b < inputs.size(); ++b) {
    if (inputs[b].size() != static_cast<Eigen::Index>(def.inputs[b].size))
      throw std::invalid_argument(def.name + ": input '" + def.inputs[b].name + "' has " +
                                  std::to_string(def.inputs[b].size) + " entries, " +
                                  std::to_string(inputs[b].size()) + " given");
    in.push_back(inputs[b].data());
  }
  std::vector<Eigen::VectorXd> out;
  std::vector<double*> out_ptr;
  for (const codegen::OutputBlock& b : def.outputs) out.emplace_back(Eigen::VectorXd::Zero(b.size()));
  for (Eigen::VectorXd& o : out) out_ptr.push_back(o.data());
  std::vector<double> work(f.workSize());
  f.evaluate(in.data(), out_ptr.data(), work.data());
  return out;
}

// An output block's doubles as its rows x cols matrix (a sparse block's missing entries
// are 0; with symmetric_lower, a lower-triangle block is mirrored to the full matrix).
Eigen::MatrixXd blockMatrix(const codegen::OutputBlock& block, const Eigen::VectorXd& values,
                            bool symmetric_lower = false);

}  // namespace robodiff
