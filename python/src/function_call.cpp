// Evaluating a Function from Python: keyword arrays checked (never converted), handed
// to the C++ Function where they are (one array per block, knot after knot), evaluated
// without the GIL straight into new numpy arrays or the caller's out= arrays.
#include "function_call.hpp"

#include <algorithm>
#include <memory_resource>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>

#include "array_views.hpp"
#include "errors.hpp"
#include "numpy_api.hpp"
#include "robodiff/language/suggest.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

// An array's shape, at most (knots, rows, cols): fixed size, so never allocated.
struct ArrayShape {
  std::size_t dims[3] = {};
  std::size_t size = 0;
  void push(std::size_t d) { dims[size++] = d; }
};

// A new C-contiguous float64 numpy array of `shape` (numpy owns its memory), and where
// its values are.
nb::object newDoubleArray(const ArrayShape& shape, double** data) {
  npy_intp dims[3];
  for (std::size_t i = 0; i < shape.size; ++i) dims[i] = static_cast<npy_intp>(shape.dims[i]);
  nb::object array = nb::steal(PyArray_SimpleNew(static_cast<int>(shape.size), dims, NPY_DOUBLE));
  if (!array.is_valid()) throw nb::python_error();
  *data = static_cast<double*>(PyArray_DATA(reinterpret_cast<PyArrayObject*>(array.ptr())));
  return array;
}

// A numpy int32 array holding `values` (a CSR pattern), made once per Function.
nb::object int32Array(const std::vector<std::uint32_t>& values) {
  auto* memory = new std::int32_t[std::max<std::size_t>(values.size(), 1)];
  std::copy(values.begin(), values.end(), memory);
  nb::capsule owner(memory, [](void* p) noexcept { delete[] static_cast<std::int32_t*>(p); });
  const std::size_t shape[1] = {values.size()};
  return nb::ndarray<nb::numpy, std::int32_t>(memory, 1, shape, owner).cast();
}

nb::object importCsrMatrix() {
  try {
    return nb::module_::import_("scipy.sparse").attr("csr_matrix");
  } catch (const nb::python_error&) {
    return nb::none();  // scipy is optional: sparse outputs are CSR tuples without it
  }
}

// The array shape one output has: (rows,) for a value vector, (rows, cols), (nnz,) for
// a sparse block's values; with a leading knot axis in a batch.
ArrayShape arrayShape(const OutputShape& o, bool batch, std::size_t knots) {
  ArrayShape shape;
  if (batch) shape.push(knots);
  if (o.sparse || o.vector) {
    shape.push(o.values);
  } else {
    shape.push(o.rows);
    shape.push(o.cols);
  }
  return shape;
}

std::string shapeOf(const ArrayShape& shape) {
  std::string text = "(";
  for (std::size_t i = 0; i < shape.size; ++i) text += (i ? ", " : "") + std::to_string(shape.dims[i]);
  return text + (shape.size == 1 ? ",)" : ")");
}

bool hasShape(const DoubleArrayView& view, const ArrayShape& shape) {
  if (view.ndim() != static_cast<int>(shape.size)) return false;
  for (std::size_t i = 0; i < shape.size; ++i)
    if (view.dim(static_cast<int>(i)) != shape.dims[i]) return false;
  return true;
}

// " (did you mean 'q'?)" with the one closest name, or "" when none is close
// (language::closestNames: the same hint the spec errors give).
std::string suggestion(const std::string& given, const std::vector<std::string>& names) {
  const std::vector<std::string> closest = language::closestNames(given, names, 1);
  return closest.empty() ? "" : " (did you mean '" + closest.front() + "'?)";
}

}  // namespace

// One call's arguments and output arrays, in memory from the call's stack (a call
// allocates nothing on the heap for them).
struct PyFunction::Arguments {
  explicit Arguments(std::pmr::memory_resource* memory)
      : inputs(memory), out_objects(memory), out_views(memory), arrays(memory), targets(memory) {}
  std::pmr::vector<DoubleArrayView> inputs;     // in input order
  std::pmr::vector<nb::handle> out_objects;     // per output: the caller's array, or null
  std::pmr::vector<DoubleArrayView> out_views;  // per output (empty views where not given)
  std::pmr::vector<nb::object> arrays;          // per output: what the call returns
  std::pmr::vector<double*> targets;            // per output: where its values go
  std::size_t knots = 1;
  bool batch = false;
};

PyFunction::PyFunction(client::Function function) : function_(std::move(function)) {
  out_key_ = nb::steal(PyUnicode_InternFromString("out"));
  const rpc::GetFunctionReply& layout = function_.layout();
  for (const rpc::InputBlock& b : layout.inputs) {
    input_names_.push_back(b.name);
    input_sizes_.push_back(b.size);
    input_keys_.push_back(nb::str(b.name.c_str()));
  }
  bool any_sparse = false;
  for (const rpc::OutputBlock& b : layout.outputs) {
    OutputShape o;
    o.name = b.name;
    o.rows = b.rows;
    o.cols = b.cols;
    o.sparse = b.layout == rpc::OutputLayout::SparseCsr;
    o.vector = !o.sparse && b.kind == rpc::OutputKind::Value && b.cols == 1;
    o.values = o.sparse ? b.nnz : std::size_t{b.rows} * b.cols;
    outputs_.push_back(o);
    output_names_.push_back(b.name);
    output_keys_.push_back(nb::str(b.name.c_str()));
    csr_indices_.push_back(o.sparse ? int32Array(b.col_indices) : nb::none());
    csr_indptr_.push_back(o.sparse ? int32Array(b.row_offsets) : nb::none());
    any_sparse = any_sparse || o.sparse;
  }
  csr_matrix_ = any_sparse ? importCsrMatrix() : nb::none();
}

std::string PyFunction::inputsText() const {
  std::string text;
  for (std::size_t i = 0; i < input_names_.size(); ++i)
    text += (i ? ", " : "") + input_names_[i] + " " + shapeText(input_sizes_[i]);
  return text;
}

std::string PyFunction::outputsText() const {
  std::string text;
  for (std::size_t i = 0; i < outputs_.size(); ++i)
    text += (i ? ", " : "") + outputs_[i].name + " " + shapeOf(arrayShape(outputs_[i], false, 1));
  return text;
}

void PyFunction::refuseNames(nb::kwargs kwargs) const {
  for (auto [key, value] : kwargs) {
    const std::string name = textOf(key);
    if (name != "out" && std::find(input_names_.begin(), input_names_.end(), name) == input_names_.end())
      throw nb::type_error(("unknown input '" + name + "'" + suggestion(name, input_names_) + "; the inputs are " +
                            inputsText())
                               .c_str());
  }
  for (std::size_t i = 0; i < input_names_.size(); ++i)
    if (!PyDict_Contains(kwargs.ptr(), input_keys_[i].ptr()))
      throw nb::type_error(("missing input '" + input_names_[i] + "'; the inputs are " + inputsText()).c_str());
  throw nb::type_error(("the inputs are " + inputsText()).c_str());
}

void PyFunction::checkInputShapes(Arguments& args) const {
  if (args.inputs.empty()) return;
  args.batch = args.inputs[0].ndim() == 2;
  args.knots = args.batch ? args.inputs[0].dim(0) : 1;
  for (std::size_t i = 0; i < args.inputs.size(); ++i) {
    const DoubleArrayView& v = args.inputs[i];
    const std::size_t n = input_sizes_[i];
    if (args.batch ? (v.ndim() == 2 && v.dim(0) == args.knots && v.dim(1) == n) : (v.ndim() == 1 && v.dim(0) == n))
      continue;
    std::string problem = "input '" + input_names_[i] + "': shape " + v.shapeText() + " given; " + shapeText(n) +
                          " for one knot or (N, " + std::to_string(n) + ") for N knots is needed";
    if (i > 0)
      problem += ", like the first input '" + input_names_[0] + "' " + args.inputs[0].shapeText() +
                 " (every input one knot, or every input the same N knots)";
    throw nb::value_error(problem.c_str());
  }
}

void PyFunction::parseOut(nb::handle out, Arguments& args) const {
  args.out_objects.assign(outputs_.size(), nb::handle());
  args.out_views.resize(outputs_.size());
  if (!out.is_valid() || out.is_none()) return;
  if (!PyDict_Check(out.ptr()))
    throw nb::type_error(("out: " + std::string(Py_TYPE(out.ptr())->tp_name) +
                          " given; a dict of numpy arrays by output name is needed (outputs: " + outputsText() + ")")
                             .c_str());
  std::size_t found = 0;
  for (std::size_t j = 0; j < outputs_.size(); ++j) {
    PyObject* given = PyDict_GetItemWithError(out.ptr(), output_keys_[j].ptr());  // str keys: never an error
    if (given == nullptr) continue;
    ++found;
    DoubleArrayView view(given, outputs_[j].name, true);
    const ArrayShape shape = arrayShape(outputs_[j], args.batch, args.knots);
    if (!hasShape(view, shape))
      throw nb::value_error((argumentLabel(outputs_[j].name, true) + ": shape " + view.shapeText() + " given; " + shapeOf(shape) + " is needed" +
                             (outputs_[j].sparse ? " (a sparse output's nnz values, in CSR order)" : ""))
                                .c_str());
    args.out_objects[j] = given;
    args.out_views[j] = std::move(view);
  }
  if (found == static_cast<std::size_t>(PyDict_Size(out.ptr()))) return;
  for (auto [key, value] : nb::borrow<nb::dict>(out)) {
    const std::string name = textOf(key);
    if (std::find(output_names_.begin(), output_names_.end(), name) == output_names_.end())
      throw nb::type_error(("out: unknown output '" + name + "'" + suggestion(name, output_names_) + "; the outputs are " +
                            outputsText())
                               .c_str());
  }
}

void PyFunction::parse(nb::kwargs kwargs, Arguments& args) const {
  PyObject* kw = kwargs.ptr();
  PyObject* out = PyDict_GetItemWithError(kw, out_key_.ptr());  // borrowed
  if (static_cast<std::size_t>(PyDict_Size(kw)) != input_names_.size() + (out ? 1 : 0)) refuseNames(kwargs);
  args.inputs.reserve(input_names_.size());
  for (std::size_t i = 0; i < input_names_.size(); ++i) {
    PyObject* given = PyDict_GetItemWithError(kw, input_keys_[i].ptr());  // borrowed
    if (given == nullptr) refuseNames(kwargs);
    args.inputs.emplace_back(given, input_names_[i], false);
  }
  checkInputShapes(args);
  parseOut(out, args);
}

nb::object PyFunction::sparseResult(std::size_t block, nb::object data, bool batch) const {
  const OutputShape& o = outputs_[block];
  nb::tuple shape = nb::make_tuple(o.rows, o.cols);
  if (batch || csr_matrix_.is_none()) return nb::make_tuple(data, csr_indices_[block], csr_indptr_[block], shape);
  return csr_matrix_(nb::make_tuple(data, csr_indices_[block], csr_indptr_[block]), nb::arg("shape") = shape,
                     nb::arg("copy") = false);
}

// The output arrays a call writes: the caller's out= arrays, else new ones.
void PyFunction::outputArrays(Arguments& args) const {
  args.arrays.resize(outputs_.size());
  args.targets.resize(outputs_.size());
  for (std::size_t j = 0; j < outputs_.size(); ++j) {
    if (args.out_objects[j].is_valid()) {
      args.arrays[j] = nb::borrow(args.out_objects[j]);
      args.targets[j] = args.out_views[j].data();
    } else {
      args.arrays[j] = newDoubleArray(arrayShape(outputs_[j], args.batch, args.knots), &args.targets[j]);
    }
  }
}

nb::dict PyFunction::call(nb::kwargs kwargs) const {
  std::byte stack[2048];
  std::pmr::monotonic_buffer_resource memory(stack, sizeof stack);
  Arguments args(&memory);
  parse(kwargs, args);
  outputArrays(args);
  // Each array is one block, knot after knot: the library's own layout, so in process
  // the arrays are evaluated where they are (client::Function::evaluateBlocks).
  std::pmr::vector<const double*> inputs(&memory);
  for (const DoubleArrayView& view : args.inputs) inputs.push_back(view.data());
  if (args.knots > 0) {
    Status status;
    {
      nb::gil_scoped_release release;
      status = function_.evaluateBlocks(args.knots, inputs, args.targets, args.batch);
    }
    if (!status.ok()) raiseStatus(status);
  }
  nb::dict result;
  for (std::size_t j = 0; j < outputs_.size(); ++j) {
    nb::object value = outputs_[j].sparse ? sparseResult(j, args.arrays[j], args.batch) : std::move(args.arrays[j]);
    PyDict_SetItem(result.ptr(), output_keys_[j].ptr(), value.ptr());
  }
  return result;
}

}  // namespace robodiff::python
