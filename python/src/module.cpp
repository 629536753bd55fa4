// _robodiff: the compiled half of the Python package robodiff (robodiff/__init__.py wraps
// it). Errors become robodiff.Error (robodiff/errors.py), imported while this module loads.
#include "bindings.hpp"
#include "errors.hpp"
#include "numpy_api.hpp"

NB_MODULE(_robodiff, m) {
  m.doc() = "robodiff's compiled bindings over the C++ client (use the package robodiff, not this module)";
  robodiff::python::importNumpy();
  robodiff::python::registerErrorTranslator();
  robodiff::python::bindFunction(m);
  robodiff::python::bindClient(m);
  robodiff::python::bindReference(m);
  robodiff::python::bindCheck(m);
  robodiff::python::bindWarmup(m);
  robodiff::python::bindCache(m);
  robodiff::python::bindJobs(m);
  robodiff::python::bindTiming(m);
}
