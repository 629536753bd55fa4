#pragma once
// robodiff.Error from C++: a Status or a ClientError becomes the Python exception
// robodiff.Error (robodiff/errors.py) carrying the status code's name and the message.
#include <nanobind/nanobind.h>

#include "robodiff/schema/status.hpp"

namespace robodiff::python {

// Sets robodiff.Error(code name, message) as the current Python error and throws
// nanobind::python_error, which nanobind passes on to Python.
[[noreturn]] void raiseStatus(const Status& status);

// Translates client::ClientError thrown inside any binding into robodiff.Error.
void registerErrorTranslator();

// Inside a raw CPython slot (no nanobind dispatch around it): sets the Python error the
// exception being handled stands for, as nanobind's dispatch would. Call from a catch.
void setErrorFromCurrentException() noexcept;

}  // namespace robodiff::python
