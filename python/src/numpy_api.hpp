#pragma once
// numpy's C API for the hot path (array checks and new arrays without going through
// Python calls or the buffer protocol). Every file of the module includes this header;
// numpy_api.cpp alone defines the API table, filled by importNumpy() at module load.
#include <Python.h>

#define PY_ARRAY_UNIQUE_SYMBOL robodiff_numpy_api
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#ifndef ROBODIFF_NUMPY_API_DEFINE
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

namespace robodiff::python {

// Loads numpy's C API; throws nanobind::python_error when numpy does not import.
void importNumpy();

}  // namespace robodiff::python
