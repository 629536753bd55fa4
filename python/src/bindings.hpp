#pragma once
// The parts of the _robodiff module, each registered by its own file.
#include <nanobind/nanobind.h>

namespace robodiff::python {

void bindClient(nanobind::module_& m);    // client_binding.cpp: Client, ModelInfo
void bindFunction(nanobind::module_& m);  // function_binding.cpp: Function

}  // namespace robodiff::python
