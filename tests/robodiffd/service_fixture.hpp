// What the end-to-end tests share: a RouDi and a robodiffd per test (real processes),
// connections over either transport, and the reference an answer is checked against
// (core/dynamics on doubles, finite differences for Jacobians: independent of tracing,
// differentiation, code generation and the service).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "robodiff/client/connection.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/shm_connection.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiffd/robodiffd_process.hpp"
#include "shm/roudi_fixture.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

// RNEA with its Jacobian wrt [q, v, a], built quickly (O1, no -march=native).
inline const char* kRneaJacobianSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}],
        "build": {"optimization": "O1", "march_native": false}})";

inline std::string arm7Text() { return readFile(sourceDir() / "examples/robots/arm7.urdf"); }

// A connection over `transport` ("iceoryx" or "dds") to the test's robodiffd.
inline std::unique_ptr<client::Connection> connectTo(const std::string& transport,
                                                     std::chrono::milliseconds timeout = std::chrono::seconds(30),
                                                     rpc::SchemaVersion version = {}) {
  if (transport == "dds") {
    client::DdsConnectionOptions options;
    options.domain_id = static_cast<std::uint32_t>(testDomain());
    options.connection.default_timeout = timeout;
    options.connection.schema_version = version;
    return client::connectDds(options);
  }
  client::ShmConnectionOptions options;
  options.default_timeout = timeout;
  options.schema_version = version;
  options.require_server = false;  // a test may start the server after connecting
  return client::connectShm(options);
}

// RNEA and its Jacobian at one state, from core/dynamics and central differences.
struct RneaReference {
  Eigen::VectorXd inputs;  // q, v, a concatenated
  Eigen::VectorXd tau;
  Eigen::MatrixXd jacobian;  // nv x 3nv

  static RneaReference at(const Model& model, std::uint64_t seed) {
    const FunctionSpec spec = parseFunctionSpec(kRneaJacobianSpec);
    const std::vector<Eigen::VectorXd> all = randomRuntimeInputs(model, spec, seed);
    RneaReference r;
    r.inputs.resize(model.nq + 2 * model.nv);
    r.inputs << all[0], all[1], all[2];
    r.tau = referenceValue(model, spec, all);
    r.jacobian = finiteDifferenceJacobian(model, spec, all, {"q", "v", "a"});
    return r;
  }

  // outputs = tau (nv) then the Jacobian row-major (nv x 3nv).
  ::testing::AssertionResult matches(const std::vector<double>& outputs, double tol_value = 1e-9,
                                     double tol_jacobian = 1e-5) const {
    const Eigen::Index nv = tau.size();
    if (outputs.size() != static_cast<std::size_t>(nv + nv * 3 * nv))
      return ::testing::AssertionFailure() << outputs.size() << " outputs";
    for (Eigen::Index i = 0; i < nv; ++i)
      if (std::abs(outputs[i] - tau[i]) > tol_value * (1 + std::abs(tau[i])))
        return ::testing::AssertionFailure() << "tau[" << i << "] " << outputs[i] << " vs " << tau[i];
    for (Eigen::Index r = 0; r < nv; ++r)
      for (Eigen::Index c = 0; c < 3 * nv; ++c) {
        const double got = outputs[nv + r * 3 * nv + c], want = jacobian(r, c);
        if (std::abs(got - want) > tol_jacobian * (1 + std::abs(want)))
          return ::testing::AssertionFailure() << "J(" << r << "," << c << ") " << got << " vs " << want;
      }
    return ::testing::AssertionSuccess();
  }
};

}  // namespace robodiff::testing
