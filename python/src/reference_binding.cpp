// robodiff._robodiff.ReferenceModel: core/dynamics in double on numpy arrays, the same
// code `robodiff check` compares generated functions with (referenceValue), for
// robodiff.reference (robodiff/reference.py documents each function).
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "array_views.hpp"
#include "bindings.hpp"
#include "reference_model.hpp"
#include "robodiff/client/client.hpp"
#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/lie_group.hpp"
#include "robodiff/dynamics/regressor.hpp"
#include "robodiff/functions/model_function.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace nb = nanobind;

namespace robodiff::python {

ReferenceModel::ReferenceModel(const std::string& urdf_text, bool floating_base, const std::string& expected_id) {
  try {
    model_ = std::make_shared<const Model>(
        loadUrdfString(urdf_text, floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed));
  } catch (const std::exception& e) {
    throw client::ClientError({StatusCode::InvalidArgument, e.what()});
  }
  id_ = canonicalHash(*model_);
  if (!expected_id.empty() && id_ != expected_id)
    throw client::ClientError({StatusCode::FailedPrecondition,
                               "the robot parsed for the reference (model " + id_.substr(0, 12) +
                                   ") is not the one loaded (model " + expected_id.substr(0, 12) +
                                   "): its URDF file changed since; load it again"});
}

namespace {

// A new C-contiguous float64 numpy array holding `values` row-major as rows x cols (a
// 1-D array of rows when `vector`).
nb::object numpyArray(const Eigen::VectorXd& values, std::size_t rows, std::size_t cols, bool vector) {
  auto* memory = new double[std::max<std::size_t>(values.size(), 1)];
  std::memcpy(memory, values.data(), static_cast<std::size_t>(values.size()) * sizeof(double));
  nb::capsule owner(memory, [](void* p) noexcept { delete[] static_cast<double*>(p); });
  const std::size_t shape[2] = {rows, cols};
  return nb::ndarray<nb::numpy, double>(memory, vector ? 1 : 2, shape, owner).cast();
}

nb::object numpyVector(const Eigen::VectorXd& v) {
  return numpyArray(v, static_cast<std::size_t>(v.size()), 1, true);
}

// A 1-D float64 array of `size` finite numbers, copied; refused naming the argument, what
// was given and what is needed (`what`: "nq", "nv").
Eigen::VectorXd vectorArgument(nb::handle object, const std::string& name, int size, const char* what) {
  const DoubleArrayView view(object, name, false);
  if (view.ndim() != 1 || view.dim(0) != static_cast<std::size_t>(size))
    throw nb::value_error((argumentLabel(name, false) + ": shape " + view.shapeText() + " given; " +
                           shapeText(static_cast<std::size_t>(size)) + " is needed (" + what + " of the model)")
                              .c_str());
  const Eigen::Map<const Eigen::VectorXd> values(view.data(), size);
  for (Eigen::Index i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]))
      throw nb::value_error((argumentLabel(name, false) + ": entry " + std::to_string(i) + " is " +
                             textOf(nb::float_(values[i])) + "; finite numbers are needed")
                                .c_str());
  return values;
}

Eigen::VectorXd inputArgument(const Model& model, nb::handle object, const std::string& name) {
  const int size = inputSize(model, name);
  return vectorArgument(object, name, size, name == "q" ? "nq" : "nv");
}

const FunctionInfo& modelFunction(const std::string& name) {
  std::string names;
  for (const FunctionInfo& info : modelFunctions()) {
    if (name == info.name) return info;
    names += (names.empty() ? "" : ", ") + std::string(info.name);
  }
  throw nb::value_error(("unknown function '" + name + "' (" + names + ")").c_str());
}

// The value of model function `name` at `inputs` (its inputs in order), shaped as the
// spec's value: (n,) for a vector, (rows, cols) for a matrix.
nb::object evaluate(const ReferenceModel& m, const std::string& name, const std::vector<nb::handle>& inputs,
                    const std::string& frame, const std::string& reference) {
  const FunctionInfo& info = modelFunction(name);
  if (inputs.size() != info.inputs.size())
    throw nb::type_error((name + " takes " + std::to_string(info.inputs.size()) + " inputs, " +
                          std::to_string(inputs.size()) + " given").c_str());
  FunctionSpec spec;
  spec.function = info.function;
  spec.frame = frame;
  spec.reference = parseReferenceFrame(reference);  // std::invalid_argument: ValueError
  std::vector<Eigen::VectorXd> all;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    spec.inputs.push_back({info.inputs[k], std::nullopt});
    all.push_back(inputArgument(m.model(), inputs[k], info.inputs[k]));
  }
  try {
    resolveFrame(m.model(), spec);
  } catch (const SpecError& e) {
    throw nb::value_error(e.what());
  }
  const auto [rows, cols] = valueShape(m.model(), info.function);
  return numpyArray(referenceValue(m.model(), spec, all), static_cast<std::size_t>(rows),
                    static_cast<std::size_t>(cols), cols == 1);
}

nb::object randomConfigurationOf(const ReferenceModel& m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  return numpyVector(randomConfiguration(m.model(), rng));
}

nb::object integrateOf(const ReferenceModel& m, nb::handle q, nb::handle v) {
  return numpyVector(integrateConfiguration<double>(m.model(), inputArgument(m.model(), q, "q"),
                                                    vectorArgument(v, "v", m.model().nv, "nv")));
}

nb::object differenceOf(const ReferenceModel& m, nb::handle q0, nb::handle q1) {
  return numpyVector(differenceConfiguration<double>(m.model(), vectorArgument(q0, "q0", m.model().nq, "nq"),
                                                     vectorArgument(q1, "q1", m.model().nq, "nq")));
}

}  // namespace

void bindReference(nb::module_& m) {
  nb::class_<ReferenceModel>(m, "ReferenceModel",
                             "A robot parsed in this process for robodiff.reference and robodiff.check "
                             "(robodiff.Model keeps one).")
      .def(nb::init<const std::string&, bool, const std::string&>(), nb::arg("urdf_text"),
           nb::arg("floating_base") = false, nb::arg("expected_id") = "",
           "Parses URDF text; with expected_id, refuses a robot whose canonical hash differs.")
      .def_prop_ro("id", &ReferenceModel::id, "The canonical hash of the parsed robot.")
      .def_prop_ro("nq", [](const ReferenceModel& r) { return r.model().nq; }, "Configuration size.")
      .def_prop_ro("nv", [](const ReferenceModel& r) { return r.model().nv; }, "Velocity size.")
      .def("evaluate", &evaluate, nb::arg("function"), nb::arg("inputs"), nb::arg("frame") = "",
           nb::arg("reference") = "LOCAL_WORLD_ALIGNED",
           "The value of a model function (rnea, aba, crba, gravity, nle, fk, frame_jacobian, com, regressor, "
           "minv) at its inputs in order, in double: (n,) for a vector, (rows, cols) for a matrix.")
      .def("neutral", [](const ReferenceModel& r) { return numpyVector(neutralConfiguration(r.model())); },
           "The neutral configuration (zeros; the identity quaternion for a free-flyer).")
      .def("random_configuration", &randomConfigurationOf, nb::arg("seed"),
           "A random configuration within the limits, as `robodiff check` draws them.")
      .def("integrate", &integrateOf, nb::arg("q"), nb::arg("v"), "q (+) v on the configuration manifold.")
      .def("difference", &differenceOf, nb::arg("q0"), nb::arg("q1"),
           "q1 (-) q0: the tangent vector d with integrate(q0, d) == q1.")
      .def("inertial_parameters", [](const ReferenceModel& r) { return numpyVector(inertialParameters(r.model())); },
           "The inertial parameters, 10 per joint, such that regressor(q, v, a) @ pi == rnea(q, v, a).");
}

}  // namespace robodiff::python
