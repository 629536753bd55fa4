#pragma once
// A robodiff Function as Python calls it: keyword inputs (one knot as 1-D arrays, or N
// knots as (N, n) arrays), outputs as numpy arrays by name, optionally written into
// preallocated arrays (out=).
#include <cstddef>
#include <string>
#include <vector>

#include <nanobind/nanobind.h>

#include "robodiff/client/client.hpp"

namespace robodiff::python {

struct OutputShape {
  std::string name;
  std::size_t rows = 0, cols = 0;
  bool sparse = false;         // CSR: `values` doubles are its nnz values
  bool vector = false;         // a value with one column: a 1-D array
  std::size_t values = 0;      // doubles per knot
};

class PyFunction {
 public:
  explicit PyFunction(client::Function function);

  const client::Function& function() const { return function_; }
  const std::vector<std::string>& inputNames() const { return input_names_; }
  const std::vector<std::size_t>& inputSizes() const { return input_sizes_; }
  const std::vector<OutputShape>& outputs() const { return outputs_; }

  // fn(q=..., v=..., out={...}): the dict of outputs by name. Raises TypeError or
  // ValueError for wrong arguments, robodiff.Error for a failed evaluation. The GIL is
  // released while the function runs.
  nanobind::dict call(nanobind::kwargs kwargs) const;

  std::string inputsText() const;   // "q (7,), v (7,), a (7,)"
  std::string outputsText() const;  // "value (7,), jacobian (7, 21)"

 private:
  struct Arguments;
  void parse(nanobind::kwargs kwargs, Arguments& args) const;
  void checkInputShapes(Arguments& args) const;
  void parseOut(nanobind::handle out, Arguments& args) const;
  nanobind::object sparseResult(std::size_t block, nanobind::object data, bool batch) const;
  void outputArrays(Arguments& args) const;

  [[noreturn]] void refuseNames(nanobind::kwargs kwargs) const;

  client::Function function_;
  std::vector<std::string> input_names_;
  std::vector<std::size_t> input_sizes_;
  std::vector<OutputShape> outputs_;
  std::vector<std::string> output_names_;
  std::vector<nanobind::object> input_keys_, output_keys_;  // the names as Python str, for dict look-ups
  std::vector<nanobind::object> csr_indices_, csr_indptr_;  // per output; None when dense
  nanobind::object csr_matrix_;
  nanobind::object out_key_;  // "out", interned  // scipy.sparse.csr_matrix, or None without scipy
};

}  // namespace robodiff::python
