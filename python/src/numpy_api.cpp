// The one definition of numpy's C API table (numpy_api.hpp).
#define ROBODIFF_NUMPY_API_DEFINE
#include "numpy_api.hpp"

#include <nanobind/nanobind.h>

namespace robodiff::python {

void importNumpy() {
  if (_import_array() < 0) throw nanobind::python_error();
}

}  // namespace robodiff::python
