// robodiff.Function: a compiled function's handle, called with numpy arrays.
#include <nanobind/stl/string.h>

#include "bindings.hpp"
#include "errors.hpp"
#include "function_call.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

nb::dict inputShapes(const PyFunction& f) {
  nb::dict shapes;
  for (std::size_t i = 0; i < f.inputNames().size(); ++i)
    shapes[f.inputNames()[i].c_str()] = nb::make_tuple(f.inputSizes()[i]);
  return shapes;
}

nb::dict outputShapes(const PyFunction& f) {
  nb::dict shapes;
  for (const OutputShape& o : f.outputs())
    shapes[o.name.c_str()] = o.vector ? nb::make_tuple(o.rows) : nb::make_tuple(o.rows, o.cols);
  return shapes;
}

nb::list sparseOutputs(const PyFunction& f) {
  nb::list names;
  for (const OutputShape& o : f.outputs())
    if (o.sparse) names.append(o.name);
  return names;
}

// Function's tp_call. CPython hands it the keywords in one dict, which goes
// straight to PyFunction::call: a def("__call__") would pass through a bound
// method and a second keyword dict (about 0.3 µs a call). Errors are set as
// nanobind's dispatch sets them.
PyObject* callFunction(PyObject* self, PyObject* args, PyObject* kwargs) noexcept {
  try {
    if (PyTuple_GET_SIZE(args) != 0)
      throw nb::type_error("robodiff.Function takes its inputs by name: fn(q=..., v=..., ...)");
    nb::kwargs named = kwargs != nullptr ? nb::borrow<nb::kwargs>(kwargs) : nb::kwargs();
    return nb::inst_ptr<PyFunction>(self)->call(named).release().ptr();
  } catch (...) {
    setErrorFromCurrentException();
    return nullptr;
  }
}

PyType_Slot kFunctionSlots[] = {{Py_tp_call, reinterpret_cast<void*>(&callFunction)}, {0, nullptr}};

}  // namespace

void bindFunction(nb::module_& m) {
  nb::class_<PyFunction>(m, "Function",
                         "A function of a robot compiled by robodiff (from Model.function): call "
                         "it with numpy "
                         "arrays by input name.\n\n"
                         "fn(q=..., v=..., ..., out=None) -> dict of numpy arrays by output "
                         "name.\n\n"
                         "Each input is a C-contiguous float64 array: shape (n,) for one knot, or "
                         "(N, n) for N knots\n"
                         "evaluated in one batched call (the outputs then have a leading N axis). "
                         "Anything else\n"
                         "(another dtype, a strided view, a wrong shape, a missing or unknown "
                         "name) raises\n"
                         "TypeError or ValueError: nothing is converted or copied silently.\n"
                         "Outputs: a value vector as (rows,), a dense matrix as (rows, cols), a "
                         "sparse one as a\n"
                         "scipy.sparse.csr_matrix when scipy imports (else, and in batches, the "
                         "tuple\n"
                         "(data, indices, indptr, shape)). out: a dict of preallocated arrays by "
                         "output name\n"
                         "(a sparse output's array holds its nnz values), written in place and "
                         "returned as\n"
                         "they are; outputs not in it are allocated. The GIL is released while "
                         "the function\n"
                         "runs. A failed evaluation (e.g. NaN inputs) raises robodiff.Error with "
                         "its code.",
                         nb::type_slots(kFunctionSlots))
      .def_prop_ro("inputs", &inputShapes, "The inputs in call order: {name: (n,)}.")
      .def_prop_ro("outputs", &outputShapes,
                   "The outputs in order: {name: shape} ((rows,) for a value "
                   "vector, else (rows, cols)).")
      .def_prop_ro("sparse_outputs", &sparseOutputs, "The names of the outputs returned in CSR form.")
      .def_prop_ro(
          "id", [](const PyFunction& f) { return f.function().id(); },
          "The function's id (a content hash of the model and the spec).")
      .def_prop_ro(
          "mode", [](const PyFunction& f) { return std::string(client::toString(f.function().mode())); },
          "How it evaluates now: 'local' (in this process), 'shm' or 'dds' "
          "(through robodiffd).")
      .def("__repr__", [](const PyFunction& f) {
        return "<robodiff.Function " + f.function().id().substr(0, 12) + " (" + f.inputsText() + ") -> (" +
               f.outputsText() + "), " + client::toString(f.function().mode()) + ">";
      });
}

}  // namespace robodiff::python
