#include "robodiff/codegen/function_definition.hpp"

#include <set>
#include <stdexcept>

namespace robodiff::codegen {
namespace {

bool isCIdentifier(const std::string& s) {
  if (s.empty() || (s[0] >= '0' && s[0] <= '9')) return false;
  for (char c : s) {
    bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}

[[noreturn]] void fail(const FunctionDefinition& f, const std::string& what) {
  throw std::invalid_argument("function '" + f.name + "': " + what);
}

}  // namespace

OutputBlock OutputBlock::dense(std::string name, std::uint32_t rows, std::uint32_t cols, std::vector<NodeId> values) {
  OutputBlock b;
  b.name = std::move(name);
  b.rows = rows;
  b.cols = cols;
  b.kind = OutputKind::Dense;
  b.values = std::move(values);
  return b;
}

OutputBlock OutputBlock::sparse(std::string name, std::uint32_t rows, std::uint32_t cols,
                                std::vector<std::uint32_t> row_ptr, std::vector<std::uint32_t> col_idx,
                                std::vector<NodeId> values) {
  OutputBlock b;
  b.name = std::move(name);
  b.rows = rows;
  b.cols = cols;
  b.kind = OutputKind::Sparse;
  b.row_ptr = std::move(row_ptr);
  b.col_idx = std::move(col_idx);
  b.values = std::move(values);
  return b;
}

std::uint32_t FunctionDefinition::inputCount() const {
  std::uint64_t n = 0;
  for (const auto& b : inputs) n += b.size;
  return static_cast<std::uint32_t>(n);
}

std::uint32_t FunctionDefinition::outputCount() const {
  std::uint64_t n = 0;
  for (const auto& b : outputs) n += b.values.size();
  return static_cast<std::uint32_t>(n);
}

void FunctionDefinition::validate(const symbolic::Graph& graph) const {
  if (!isCIdentifier(name)) fail(*this, "the name must be a C identifier ([A-Za-z_][A-Za-z0-9_]*)");
  if (outputs.empty()) fail(*this, "no outputs");
  std::set<std::string> names;
  std::uint64_t total_inputs = 0;
  for (const auto& b : inputs) {
    if (b.name.empty()) fail(*this, "an input block has no name");
    if (!names.insert(b.name).second) fail(*this, "two blocks are named '" + b.name + "'");
    total_inputs += b.size;
  }
  if (total_inputs > UINT32_MAX) fail(*this, "too many inputs");
  for (const auto& b : outputs) {
    const std::string where = "output '" + b.name + "': ";
    if (b.name.empty()) fail(*this, "an output block has no name");
    if (!names.insert(b.name).second) fail(*this, "two blocks are named '" + b.name + "'");
    if (b.kind == OutputKind::Dense) {
      if (static_cast<std::uint64_t>(b.rows) * b.cols != b.values.size())
        fail(*this, where + std::to_string(b.rows) + "x" + std::to_string(b.cols) + " dense needs " +
                        std::to_string(static_cast<std::uint64_t>(b.rows) * b.cols) + " values, got " +
                        std::to_string(b.values.size()));
      if (!b.row_ptr.empty() || !b.col_idx.empty()) fail(*this, where + "a dense block has a CSR pattern");
    } else {
      if (b.row_ptr.size() != static_cast<std::size_t>(b.rows) + 1)
        fail(*this, where + "row_ptr needs rows + 1 = " + std::to_string(b.rows + 1) + " entries, got " +
                        std::to_string(b.row_ptr.size()));
      if (b.row_ptr.front() != 0 || b.row_ptr.back() != b.col_idx.size())
        fail(*this, where + "row_ptr must start at 0 and end at the number of nonzeros");
      if (b.col_idx.size() != b.values.size())
        fail(*this, where + std::to_string(b.col_idx.size()) + " column indices but " +
                        std::to_string(b.values.size()) + " values");
      for (std::uint32_t r = 0; r < b.rows; ++r) {
        if (b.row_ptr[r] > b.row_ptr[r + 1]) fail(*this, where + "row_ptr decreases at row " + std::to_string(r));
        for (std::uint32_t k = b.row_ptr[r]; k < b.row_ptr[r + 1]; ++k) {
          if (b.col_idx[k] >= b.cols) fail(*this, where + "column index " + std::to_string(b.col_idx[k]) + " out of range");
          if (k > b.row_ptr[r] && b.col_idx[k] <= b.col_idx[k - 1])
            fail(*this, where + "column indices must increase within row " + std::to_string(r));
        }
      }
    }
    for (NodeId id : b.values) {
      if (id >= graph.size()) fail(*this, where + "node " + std::to_string(id) + " is not in the graph");
    }
  }
  // Every Input node the outputs reach must be one of the declared inputs.
  std::vector<char> needed(graph.size(), 0);
  for (const auto& b : outputs)
    for (NodeId id : b.values) needed[id] = 1;
  for (std::size_t i = graph.size(); i-- > 0;) {
    if (!needed[i]) continue;
    const symbolic::Node& n = graph.node(static_cast<NodeId>(i));
    if (n.op == symbolic::Op::Input && n.index >= total_inputs)
      fail(*this, "the outputs use input " + std::to_string(n.index) + " but the input blocks hold only " +
                      std::to_string(total_inputs));
    for (int a = 0; a < symbolic::arity(n.op); ++a) needed[n.args[a]] = 1;
  }
}

}  // namespace robodiff::codegen
