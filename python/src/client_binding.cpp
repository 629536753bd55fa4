// robodiff._robodiff.Client and ModelInfo: connecting and loading, the GIL released
// while the C++ client waits (connecting, a server compiling a function).
#include <chrono>
#include <filesystem>
#include <optional>

#include <nanobind/stl/filesystem.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "function_call.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

client::ClientOptions clientOptions(const std::optional<std::string>& server,
                                    const std::optional<std::filesystem::path>& cache_dir, double timeout_seconds) {
  client::ClientOptions options;
  if (server) options.server = client::parseServerAddress(*server);  // std::invalid_argument: ValueError
  if (cache_dir) options.cache_dir = *cache_dir;
  if (!(timeout_seconds > 0)) throw nb::value_error("timeout must be a positive number of seconds");
  options.timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(timeout_seconds));
  return options;
}

}  // namespace

void bindClient(nb::module_& m) {
  nb::class_<client::ModelInfo>(m, "ModelInfo", "A robot model loaded by a Client (robodiff.Model wraps it).")
      .def_ro("id", &client::ModelInfo::id, "The model's canonical hash.")
      .def_ro("nq", &client::ModelInfo::nq, "Configuration size.")
      .def_ro("nv", &client::ModelInfo::nv, "Velocity (tangent space) size.")
      .def_ro("joint_names", &client::ModelInfo::joint_names, "Joint names, in the model's order.")
      .def_ro("frame_names", &client::ModelInfo::frame_names, "Frame names, in the model's order.");

  nb::class_<client::Client>(m, "Client", "The C++ client (robodiff.Client wraps it).")
      .def(
          "__init__",
          [](client::Client* self, std::optional<std::string> server, std::optional<std::filesystem::path> cache_dir,
             double timeout) {
            client::ClientOptions options = clientOptions(server, cache_dir, timeout);
            nb::gil_scoped_release release;
            new (self) client::Client(std::move(options));
          },
          nb::arg("server").none() = nb::none(), nb::arg("cache_dir").none() = nb::none(), nb::arg("timeout") = 30.0,
          "Connects: server None reads $ROBODIFF_SERVER (else auto); cache_dir None is the default cache.")
      .def_prop_ro("mode", [](const client::Client& c) { return std::string(client::toString(c.mode())); },
                   "The mode in use: 'local', 'shm' or 'dds'.")
      .def("load_model", &client::Client::loadModel, nb::arg("urdf_text"), nb::arg("floating_base") = false,
           nb::call_guard<nb::gil_scoped_release>(), "Loads a robot from URDF text.")
      .def("load_model_file", &client::Client::loadModelFile, nb::arg("urdf_path"), nb::arg("floating_base") = false,
           nb::call_guard<nb::gil_scoped_release>(), "Loads a robot from a URDF file.")
      .def(
          "function",
          [](client::Client& c, const client::ModelInfo& model, const std::string& spec_json) {
            client::Function f;
            {
              nb::gil_scoped_release release;
              f = c.function(model, spec_json);
            }
            return PyFunction(std::move(f));
          },
          nb::arg("model"), nb::arg("spec_json"), "A Function from a spec's JSON text; waits until it can be evaluated.")
      .def(
          "function_file",
          [](client::Client& c, const client::ModelInfo& model, const std::filesystem::path& spec_path) {
            client::Function f;
            {
              nb::gil_scoped_release release;
              f = c.functionFile(model, spec_path);
            }
            return PyFunction(std::move(f));
          },
          nb::arg("model"), nb::arg("spec_path"), "A Function from a spec file.");
}

}  // namespace robodiff::python
