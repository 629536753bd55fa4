// _robodiff._native_seconds_per_call: the same Function called from C++ in a loop, for
// bench/python (the figure a Python call is compared with, measured in the same process,
// on the same library and inputs, in the same run).
#include <algorithm>
#include <chrono>
#include <vector>

#include "array_views.hpp"
#include "bindings.hpp"
#include "errors.hpp"
#include "function_call.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

// Median over `rounds` of the mean time of `calls` evaluations of `knots` knots (one
// evaluate per call when knots == 0, else evaluateBatch), after a warm-up round.
double nativeSecondsPerCall(const PyFunction& f, nb::handle inputs, std::size_t knots, int calls, int rounds) {
  const DoubleArrayView in(inputs, "inputs", false);
  const std::size_t per_knot = f.function().inputCount();
  const std::size_t count = std::max<std::size_t>(knots, 1);
  if (in.size() != count * per_knot)
    throw nb::value_error(("inputs: " + std::to_string(in.size()) + " values given; " +
                           std::to_string(count * per_knot) + " (knots x inputs per knot) are needed")
                              .c_str());
  if (calls < 1 || rounds < 1) throw nb::value_error("calls and rounds must be positive");
  std::vector<double> out(count * f.function().outputCount());
  const std::span<const double> input(in.data(), in.size());
  std::vector<double> seconds;
  {
    nb::gil_scoped_release release;
    for (int r = -1; r < rounds; ++r) {
      const auto start = std::chrono::steady_clock::now();
      for (int c = 0; c < calls; ++c) {
        const Status s = knots == 0 ? f.function().evaluate(input, out) : f.function().evaluateBatch(knots, input, out);
        if (!s.ok()) {
          nb::gil_scoped_acquire acquire;
          raiseStatus(s);
        }
      }
      const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
      if (r >= 0) seconds.push_back(took.count() / calls);
    }
  }
  std::nth_element(seconds.begin(), seconds.begin() + seconds.size() / 2, seconds.end());
  return seconds[seconds.size() / 2];
}

}  // namespace

void bindTiming(nb::module_& m) {
  m.def("_native_seconds_per_call", &nativeSecondsPerCall, nb::arg("function"), nb::arg("inputs"), nb::arg("knots"),
        nb::arg("calls"), nb::arg("rounds") = 5,
        "For bench/python: seconds per call of the Function evaluated from C++ (knots 0: one evaluate per call; "
        "else evaluateBatch of that many knots), inputs knot-major in one float64 array.");
}

}  // namespace robodiff::python
