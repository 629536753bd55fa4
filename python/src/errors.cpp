// ClientError and Status -> robodiff.Error (defined in Python: robodiff/errors.py).
#include "errors.hpp"

#include "robodiff/client/client.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

// robodiff.errors.Error, imported once and kept for the process (never released: a
// static nb::object would be destroyed after the interpreter).
PyObject* errorType() {
  static PyObject* type = nb::object(nb::module_::import_("robodiff.errors").attr("Error")).release().ptr();
  return type;
}

// Sets robodiff.Error as the current Python error (or the error that prevented it).
void setErrorFrom(const Status& status) {
  PyObject* args = Py_BuildValue("(ss)", toString(status.code).c_str(), status.message.c_str());
  if (args == nullptr) return;
  PyObject* error = PyObject_CallObject(errorType(), args);
  Py_DECREF(args);
  if (error == nullptr) return;
  PyErr_SetObject(errorType(), error);
  Py_DECREF(error);
}

}  // namespace

void raiseStatus(const Status& status) {
  setErrorFrom(status);
  throw nb::python_error();
}

void setErrorFromCurrentException() noexcept {
  try {
    throw;
  } catch (nb::python_error& e) {
    e.restore();
  } catch (const nb::builtin_exception& e) {
    PyObject* type = e.type() == nb::exception_type::type_error    ? PyExc_TypeError
                     : e.type() == nb::exception_type::value_error ? PyExc_ValueError
                                                                   : PyExc_RuntimeError;
    PyErr_SetString(type, e.what());
  } catch (const client::ClientError& e) {
    setErrorFrom(e.status());
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
  } catch (...) {
    PyErr_SetString(PyExc_RuntimeError, "unknown C++ exception");
  }
}

void registerErrorTranslator() {
  errorType();  // imported now, while the module loads
  nb::register_exception_translator([](const std::exception_ptr& p, void*) {
    try {
      std::rethrow_exception(p);
    } catch (const client::ClientError& e) {
      setErrorFrom(e.status());
    }
  });
}

}  // namespace robodiff::python
