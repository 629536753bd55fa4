// Evaluating a Function from Python: keyword arrays checked (never converted), packed
// into one knot-major buffer per thread, evaluated without the GIL, and the outputs
// written into new numpy arrays or the caller's out= arrays.
#include "function_call.hpp"

#include <algorithm>
#include <cstring>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>

#include "array_views.hpp"
#include "errors.hpp"
#include "robodiff/language/suggest.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

// numpy.empty, looked up once (kept for the process: never released after the interpreter).
PyObject* numpyEmpty() {
  static PyObject* empty = nb::object(nb::module_::import_("numpy").attr("empty")).release().ptr();
  return empty;
}

// A new C-contiguous float64 numpy array of `shape` (numpy.empty: numpy owns it), and
// where its values are.
nb::object newDoubleArray(const std::vector<std::size_t>& shape, double** data) {
  nb::object dims = nb::steal(PyTuple_New(static_cast<Py_ssize_t>(shape.size())));
  for (std::size_t i = 0; i < shape.size(); ++i)
    PyTuple_SET_ITEM(dims.ptr(), static_cast<Py_ssize_t>(i), PyLong_FromSize_t(shape[i]));
  nb::object array = nb::steal(PyObject_CallOneArg(numpyEmpty(), dims.ptr()));  // float64, C order
  if (!array.is_valid()) throw nb::python_error();
  Py_buffer view;
  if (PyObject_GetBuffer(array.ptr(), &view, PyBUF_SIMPLE | PyBUF_WRITABLE) != 0) throw nb::python_error();
  *data = static_cast<double*>(view.buf);
  PyBuffer_Release(&view);  // numpy's memory stays with the array, which we hold
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
std::vector<std::size_t> arrayShape(const OutputShape& o, bool batch, std::size_t knots) {
  std::vector<std::size_t> shape;
  if (batch) shape.push_back(knots);
  if (o.sparse || o.vector) {
    shape.push_back(o.values);
  } else {
    shape.push_back(o.rows);
    shape.push_back(o.cols);
  }
  return shape;
}

std::string shapeOf(const std::vector<std::size_t>& shape) {
  std::string text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) text += (i ? ", " : "") + std::to_string(shape[i]);
  return text + (shape.size() == 1 ? ",)" : ")");
}

bool hasShape(const DoubleArrayView& view, const std::vector<std::size_t>& shape) {
  if (view.ndim() != static_cast<int>(shape.size())) return false;
  for (std::size_t i = 0; i < shape.size(); ++i)
    if (view.dim(static_cast<int>(i)) != shape[i]) return false;
  return true;
}

// " (did you mean 'q'?)" with the one closest name, or "" when none is close
// (language::closestNames: the same hint the spec errors give).
std::string suggestion(const std::string& given, const std::vector<std::string>& names) {
  const std::vector<std::string> closest = language::closestNames(given, names, 1);
  return closest.empty() ? "" : " (did you mean '" + closest.front() + "'?)";
}

}  // namespace

struct PyFunction::Arguments {
  std::vector<DoubleArrayView> inputs;     // in input order
  std::vector<nb::handle> out_objects;     // per output: the caller's array, or null
  std::vector<DoubleArrayView> out_views;  // per output (empty views where not given)
  std::size_t knots = 1;
  bool batch = false;
};

PyFunction::PyFunction(client::Function function) : function_(std::move(function)) {
  const rpc::GetFunctionReply& layout = function_.layout();
  for (const rpc::InputBlock& b : layout.inputs) {
    input_names_.push_back(b.name);
    input_sizes_.push_back(b.size);
    input_keys_.push_back(nb::str(b.name.c_str()));
  }
  std::size_t offset = 0;
  bool any_sparse = false;
  for (const rpc::OutputBlock& b : layout.outputs) {
    OutputShape o;
    o.name = b.name;
    o.rows = b.rows;
    o.cols = b.cols;
    o.sparse = b.layout == rpc::OutputLayout::SparseCsr;
    o.vector = !o.sparse && b.kind == rpc::OutputKind::Value && b.cols == 1;
    o.values = o.sparse ? b.nnz : std::size_t{b.rows} * b.cols;
    o.offset = offset;
    offset += o.values;
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
    PyObject* given = PyDict_GetItem(out.ptr(), output_keys_[j].ptr());
    if (given == nullptr) continue;
    ++found;
    DoubleArrayView view(given, outputs_[j].name, true);
    const std::vector<std::size_t> shape = arrayShape(outputs_[j], args.batch, args.knots);
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

PyFunction::Arguments PyFunction::parse(nb::kwargs kwargs) const {
  PyObject* kw = kwargs.ptr();
  PyObject* out = PyDict_GetItemString(kw, "out");  // borrowed
  if (static_cast<std::size_t>(PyDict_Size(kw)) != input_names_.size() + (out ? 1 : 0)) refuseNames(kwargs);
  Arguments args;
  args.inputs.reserve(input_names_.size());
  for (std::size_t i = 0; i < input_names_.size(); ++i) {
    PyObject* given = PyDict_GetItem(kw, input_keys_[i].ptr());  // borrowed
    if (given == nullptr) refuseNames(kwargs);
    args.inputs.emplace_back(given, input_names_[i], false);
  }
  checkInputShapes(args);
  parseOut(out, args);
  return args;
}

nb::object PyFunction::sparseResult(std::size_t block, nb::object data, bool batch) const {
  const OutputShape& o = outputs_[block];
  nb::tuple shape = nb::make_tuple(o.rows, o.cols);
  if (batch || csr_matrix_.is_none()) return nb::make_tuple(data, csr_indices_[block], csr_indptr_[block], shape);
  return csr_matrix_(nb::make_tuple(data, csr_indices_[block], csr_indptr_[block]), nb::arg("shape") = shape,
                     nb::arg("copy") = false);
}

nb::dict PyFunction::call(nb::kwargs kwargs) const {
  const Arguments args = parse(kwargs);
  const std::size_t in_count = function_.inputCount(), out_count = function_.outputCount();
  thread_local std::vector<double> in_buffer, out_buffer;  // no allocation after a thread's largest call
  in_buffer.resize(args.knots * in_count);
  out_buffer.resize(args.knots * out_count);
  std::size_t in_offset = 0;
  for (std::size_t i = 0; i < args.inputs.size(); ++i) {
    const std::size_t n = input_sizes_[i];
    for (std::size_t k = 0; k < args.knots; ++k)
      std::memcpy(in_buffer.data() + k * in_count + in_offset, args.inputs[i].data() + k * n, n * sizeof(double));
    in_offset += n;
  }
  if (args.knots > 0) {
    Status status;
    {
      nb::gil_scoped_release release;
      status = args.batch ? function_.evaluateBatch(args.knots, in_buffer, out_buffer)
                          : function_.evaluate(in_buffer, out_buffer);
    }
    if (!status.ok()) raiseStatus(status);
  }
  nb::dict result;
  for (std::size_t j = 0; j < outputs_.size(); ++j) {
    const OutputShape& o = outputs_[j];
    nb::object array;
    double* target = nullptr;
    if (args.out_objects[j].is_valid()) {
      array = nb::borrow(args.out_objects[j]);
      target = args.out_views[j].data();
    } else {
      array = newDoubleArray(arrayShape(o, args.batch, args.knots), &target);
    }
    for (std::size_t k = 0; k < args.knots; ++k)
      std::memcpy(target + k * o.values, out_buffer.data() + k * out_count + o.offset, o.values * sizeof(double));
    PyDict_SetItem(result.ptr(), output_keys_[j].ptr(), o.sparse ? sparseResult(j, array, args.batch).ptr() : array.ptr());
  }
  return result;
}

}  // namespace robodiff::python
