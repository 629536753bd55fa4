// A user function through the client library from a spec file (examples/specs/
// arm7_mpc_knot.json: an Euler step, a tracking cost and a collision barrier): over shared
// memory and locally, a 20-knot horizon in one evaluateBatch call equals the knots one
// by one and the double evaluation of the same expressions.
#include <cmath>

#include "client/client_fixture.hpp"
#include "robodiff/functions/reference.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;

TEST(ClientUserFunction, AHorizonInOneBatchFromASpecFile) {
  SharedServer& shared = SharedServer::get();
  const std::filesystem::path spec_path = sourceDir() / "examples/specs/arm7_mpc_knot.json";
  const FunctionSpec spec = loadFunctionSpec(spec_path.string());
  const Model& model = shared.model();
  for (const Mode mode : {Mode::Shm, Mode::Local}) {
    SCOPED_TRACE(mode == Mode::Shm ? "shm" : "local");
    Client c(shared.server().options(mode));
    const client::Function f = c.functionFile(c.loadModel(arm7Text()), spec_path);
    // Local needs the compiled library in the cache: the server builds it first.
    if (mode == Mode::Shm) {
      ASSERT_TRUE(waitFor([&] { return serverCompiled(c, f.id()); }, std::chrono::seconds(120)));
    }
    ASSERT_EQ(f.mode(), mode);
    const std::size_t knots = 20, in_n = f.inputCount(), out_n = f.outputCount();
    std::vector<double> in;
    for (std::size_t k = 0; k < knots; ++k)
      for (const Eigen::VectorXd& block : randomRuntimeInputs(model, spec, 50 + k)) in.insert(in.end(), block.begin(), block.end());
    std::vector<double> batch(knots * out_n, std::nan("")), single(out_n, std::nan(""));
    ASSERT_TRUE(f.evaluateBatch(knots, in, batch).ok());
    for (std::size_t k = 0; k < knots; k += 7) {
      ASSERT_TRUE(f.evaluate({in.data() + k * in_n, in_n}, single).ok());
      for (std::size_t i = 0; i < out_n; ++i)
        EXPECT_NEAR(batch[k * out_n + i], single[i], 1e-12 * (1 + std::fabs(single[i]))) << "knot " << k << " entry " << i;
    }
    // The first knot's values (q_next, v_next come first) against the double evaluation.
    const std::vector<Eigen::MatrixXd> expected = userReferenceOutputs(model, spec, completeInputs(spec, randomRuntimeInputs(model, spec, 50)));
    for (int i = 0; i < model.nq; ++i) EXPECT_NEAR(batch[i], expected[0](i, 0), 1e-12);
    for (int i = 0; i < model.nv; ++i) EXPECT_NEAR(batch[model.nq + i], expected[1](i, 0), 1e-12);
  }
  Client c(shared.server().options(Mode::Local));
  EXPECT_THROW(c.functionFile(c.loadModel(arm7Text()), sourceDir() / "no/such/spec.json"), client::ClientError);
}

}  // namespace
}  // namespace robodiff::testing
