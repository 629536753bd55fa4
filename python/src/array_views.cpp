// Checking a Python buffer as C-contiguous float64 with messages a user can act on.
#include "array_views.hpp"

#include "numpy_api.hpp"

#include <nanobind/stl/string.h>

#include <cstring>
#include <utility>

namespace nb = nanobind;

namespace robodiff::python {
namespace {

// "numpy.ndarray", "list", ...: the given object's type for messages.
std::string typeName(nb::handle object) {
  PyTypeObject* type = Py_TYPE(object.ptr());
  nb::object module = nb::getattr(reinterpret_cast<PyObject*>(type), "__module__", nb::none());
  const std::string name = type->tp_name;
  if (module.is_none() || name.find('.') != std::string::npos) return name;
  const std::string prefix = textOf(module);
  return prefix == "builtins" ? name : prefix + "." + name;
}

// The element type as the user knows it: the array's dtype, else the buffer's format.
std::string elementType(nb::handle object, const Py_buffer& view) {
  if (nb::hasattr(object, "dtype")) return textOf(object.attr("dtype"));
  return std::string("format '") + (view.format ? view.format : "B") + "'";
}

bool isNativeDouble(const char* format) {
  if (format == nullptr) return false;
  if (format[0] == '@' || format[0] == '=' || format[0] == '<') ++format;
  return std::strcmp(format, "d") == 0;
}

std::string stridesText(const Py_buffer& view) {
  std::string text = "(";
  for (int i = 0; i < view.ndim; ++i)
    text += (i ? ", " : "") + std::to_string(view.strides ? view.strides[i] : 0);
  return text + (view.ndim == 1 ? ",)" : ")");
}

}  // namespace

// str(object), as Python prints it.
std::string textOf(nb::handle object) {
  nb::object text = nb::steal(PyObject_Str(object.ptr()));
  if (!text.is_valid()) {
    PyErr_Clear();
    return "?";
  }
  return PyUnicode_AsUTF8(text.ptr());
}

std::string shapeText(std::size_t a) { return "(" + std::to_string(a) + ",)"; }
std::string shapeText(std::size_t a, std::size_t b) { return "(" + std::to_string(a) + ", " + std::to_string(b) + ")"; }

std::string argumentLabel(const std::string& name, bool output) {
  return output ? "out['" + name + "']" : "input '" + name + "'";
}

DoubleArrayView::DoubleArrayView(nb::handle object, const std::string& name, bool writable) {
  if (!viewNumpyArray(object, writable)) viewBuffer(object, name, writable);
}

// A float64, C-contiguous, aligned, native-order numpy array (writable when asked): its
// fields read directly, no buffer export (which costs numpy a format string per call).
bool DoubleArrayView::viewNumpyArray(nb::handle object, bool writable) {
  if (!PyArray_Check(object.ptr())) return false;
  auto* array = reinterpret_cast<PyArrayObject*>(object.ptr());
  if (PyArray_TYPE(array) != NPY_DOUBLE || !PyArray_ISCARRAY_RO(array) || !PyArray_ISNOTSWAPPED(array) ||
      (writable && !PyArray_ISWRITEABLE(array)))
    return false;  // the buffer path says what is wrong
  data_ = static_cast<double*>(PyArray_DATA(array));
  ndim_ = PyArray_NDIM(array);
  shape_ = reinterpret_cast<const Py_ssize_t*>(PyArray_DIMS(array));
  size_ = static_cast<std::size_t>(PyArray_SIZE(array));
  return true;
}

void DoubleArrayView::viewBuffer(nb::handle object, const std::string& name, bool writable) {
  const char* needed = "a C-contiguous numpy.ndarray of float64";
  if (PyObject_GetBuffer(object.ptr(), &view_, PyBUF_RECORDS_RO) != 0) {
    PyErr_Clear();
    throw nb::type_error(
        (argumentLabel(name, writable) + ": " + typeName(object) + " given; " + needed + " is needed").c_str());
  }
  const bool fits = isNativeDouble(view_.format) && view_.itemsize == sizeof(double) &&
                    PyBuffer_IsContiguous(&view_, 'C') && !(writable && view_.readonly);
  data_ = static_cast<double*>(view_.buf);
  ndim_ = view_.ndim;
  shape_ = view_.shape;
  size_ = static_cast<std::size_t>(view_.len) / sizeof(double);
  if (fits) [[likely]] {
    held_ = true;
    return;
  }
  const std::string what = argumentLabel(name, writable);
  // A throwing constructor runs no destructor: the buffer is released before each refusal.
  std::string type_problem, value_problem;
  if (!isNativeDouble(view_.format) || view_.itemsize != sizeof(double))
    type_problem = what + ": dtype " + elementType(object, view_) + " given; " + needed +
                   " is needed (convert it once, outside the loop: numpy.asarray(x, dtype=numpy.float64))";
  else if (!PyBuffer_IsContiguous(&view_, 'C'))
    value_problem = what + ": a non-contiguous array given (shape " + shapeText() + ", strides " +
                    stridesText(view_) + " bytes: a slice or a transpose); " + needed +
                    " is needed (numpy.ascontiguousarray(x) makes one)";
  else if (writable && view_.readonly)
    value_problem = what + ": a read-only array given; a writable one is needed to write into";
  PyBuffer_Release(&view_);
  if (!type_problem.empty()) throw nb::type_error(type_problem.c_str());
  throw nb::value_error(value_problem.c_str());
}

DoubleArrayView::DoubleArrayView(DoubleArrayView&& other) noexcept
    : data_(other.data_),
      ndim_(other.ndim_),
      shape_(other.shape_),
      size_(other.size_),
      view_(other.view_),
      held_(std::exchange(other.held_, false)) {}

DoubleArrayView& DoubleArrayView::operator=(DoubleArrayView&& other) noexcept {
  if (this != &other) {
    if (held_) PyBuffer_Release(&view_);
    data_ = other.data_;
    ndim_ = other.ndim_;
    shape_ = other.shape_;
    size_ = other.size_;
    view_ = other.view_;
    held_ = std::exchange(other.held_, false);
  }
  return *this;
}

DoubleArrayView::~DoubleArrayView() {
  if (held_) PyBuffer_Release(&view_);
}

std::string DoubleArrayView::shapeText() const {
  std::string text = "(";
  for (int i = 0; i < ndim_; ++i) text += (i ? ", " : "") + std::to_string(shape_[i]);
  return text + (ndim_ == 1 ? ",)" : ")");
}

}  // namespace robodiff::python
