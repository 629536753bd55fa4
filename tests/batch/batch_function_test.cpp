// BatchFunction: the compiled (through the cache and a real robodiff-worker) and the
// interpreted backends give core/dynamics' values and central-difference Jacobians, knot
// by knot, and evaluateMany (threads, batched entry point, chunk transposition) equals
// evaluate on every knot, a count that is not a multiple of the batch width included.
#include <cmath>

#include <gtest/gtest.h>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

constexpr const char* kRneaJacobian =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}]})";

class BatchFunctionTest : public ::testing::TestWithParam<batch::Backend> {
 protected:
  batch::BatchFunction open() {
    batch::BatchFunctionOptions options;
    options.backend = GetParam();
    options.cache_dir = dir_ / "cache";
    options.worker_executable = workerPath();
    options.threads = 2;
    return batch::BatchFunction::open(model_, urdf_, false, spec_, options);
  }
  TempDir dir_;
  std::string urdf_ = readFile(sourceDir() / "examples/robots/arm7.urdf");
  Model model_ = loadUrdfString(urdf_, RootJoint::Fixed, "arm7.urdf");
  FunctionSpec spec_ = parseFunctionSpec(kRneaJacobian);
};

TEST_P(BatchFunctionTest, MatchesTheReferenceAndFiniteDifferences) {
  const batch::BatchFunction f = open();
  EXPECT_EQ(f.backend(), GetParam());
  ASSERT_EQ(f.inputs().size(), 3u);
  EXPECT_EQ(f.input("v").offset, 7u);
  EXPECT_EQ(f.inputCount(), 21u);
  EXPECT_EQ(f.output("jacobian").rows, 7u);
  EXPECT_EQ(f.output("jacobian").cols, 21u);
  EXPECT_EQ(f.outputCount(), 7u + 147u);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const std::vector<Eigen::VectorXd> in = randomRuntimeInputs(model_, spec_, seed);
    Eigen::VectorXd knot(21);
    knot << in[0], in[1], in[2];
    std::vector<double> out(f.outputCount(), std::nan(""));
    f.evaluate(knot.data(), out.data());
    const Eigen::VectorXd tau = referenceValue(model_, spec_, in);
    const Eigen::MatrixXd jac = finiteDifferenceJacobian(model_, spec_, in, {"q", "v", "a"});
    for (int i = 0; i < 7; ++i) EXPECT_NEAR(out[i], tau[i], 1e-10 * (1 + std::abs(tau[i])));
    for (int r = 0; r < 7; ++r)
      for (int c = 0; c < 21; ++c) EXPECT_NEAR(out[7 + r * 21 + c], jac(r, c), 1e-5 * (1 + std::abs(jac(r, c))));
  }
}

TEST_P(BatchFunctionTest, EvaluateManyEqualsEvaluateOnEveryKnot) {
  const batch::BatchFunction f = open();
  const std::uint64_t knots = 1003;  // not a multiple of any batch width or piece
  std::vector<double> in(knots * f.inputCount());
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = std::sin(0.37 * static_cast<double>(i));
  std::vector<double> many(knots * f.outputCount(), std::nan("")), one(f.outputCount());
  std::uint64_t last_progress = 0;
  EXPECT_EQ(f.evaluateMany(knots, in.data(), many.data(), {}, [&](std::uint64_t done) { last_progress = done; }),
            knots);
  EXPECT_EQ(last_progress, knots);
  for (std::uint64_t k = 0; k < knots; ++k) {
    f.evaluate(in.data() + k * f.inputCount(), one.data());
    for (std::size_t i = 0; i < one.size(); ++i)
      ASSERT_NEAR(many[k * f.outputCount() + i], one[i], 1e-12 * (1 + std::abs(one[i]))) << "knot " << k << " entry " << i;
  }
}

TEST_P(BatchFunctionTest, CancellationStopsEarly) {
  const batch::BatchFunction f = open();
  const std::uint64_t knots = 100000;
  std::vector<double> in(knots * f.inputCount(), 0.1), out(knots * f.outputCount());
  std::atomic<int> polls{0};
  const std::uint64_t done = f.evaluateMany(knots, in.data(), out.data(), [&] { return ++polls > 3; });
  EXPECT_LT(done, knots);
}

INSTANTIATE_TEST_SUITE_P(Backends, BatchFunctionTest,
                         ::testing::Values(batch::Backend::Compiled, batch::Backend::Interpreted),
                         [](const auto& info) { return std::string(batch::toString(info.param)); });

TEST(BatchBackend, ParsesItsNames) {
  EXPECT_EQ(batch::parseBackend("compiled"), batch::Backend::Compiled);
  EXPECT_EQ(batch::parseBackend("interpreted"), batch::Backend::Interpreted);
  EXPECT_THROW(batch::parseBackend("fast"), std::invalid_argument);
}

}  // namespace
}  // namespace robodiff::testing
