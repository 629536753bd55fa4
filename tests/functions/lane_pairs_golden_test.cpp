// Derivative functions of a robot with symmetric limbs, compiled with lane pairs (seeded
// at twins: a left leg's Jacobian entry and the right leg's), against Pinocchio's
// derivatives in ../shared/golden (1e-9): Talos's RNEA d tau/d(q, v, a) and ABA
// d ddq/d(q, v, tau) on the fixed base, RNEA on the free-flyer (its ABA Jacobian, 123k
// operations, is past the size where pairs are tried).
#include <iostream>

#include <Eigen/LU>

#include <gtest/gtest.h>

#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::matricesAgree;

struct PairedCase {
  std::string robot, fn;
};

class PairedGolden : public ::testing::TestWithParam<PairedCase> {};

TEST_P(PairedGolden, PairedJacobiansMatchPinocchio) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const std::string fn = GetParam().fn;
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam().robot);
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  const int n = model.nv;
  const bool rnea = fn == "rnea";
  const std::string x = rnea ? "a" : "tau";
  FunctionSpec spec = parseFunctionSpec(R"({"function": ")" + fn + R"(", "outputs": [{"kind": "value"}, )" +
                                        R"({"kind": "jacobian", "wrt": ["q", "v", ")" + x + R"("]}]})");
  spec.build.optimization = "O1";
  testing::TempDir dir;
  const GeneratedFunctionLibrary generated = generateFunctionLibrary(model, spec, dir.path() / "out");
  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(generated.library);
  const codegen::CompiledFunction f = library.function(generated.built.definition.name);
  std::cout << GetParam().robot << " " << fn << " value + Jacobian: " << generated.info.lane_pairs << " pairs in "
            << generated.info.operations << " operations\n";
  EXPECT_EQ(generated.built.definition.lane_pairs, codegen::LanePairSeeds::Twins);
  EXPECT_GT(generated.info.lane_pairs, 0u) << "Talos's legs and arms are twins";
  for (std::size_t s = 0; s < golden.samples.size(); s += 4) {
    const auto& g = golden.samples[s];
    const std::vector<Eigen::VectorXd> out =
        evaluateBlocks(f, generated.built.definition, {g.q, g.v, rnea ? g.a : g.tau});
    const Eigen::MatrixXd J = Eigen::Map<const Eigen::MatrixXd>(out[1].data(), 3 * n, n).transpose();
    EXPECT_TRUE(matricesAgree(out[0], rnea ? g.tau : g.ddq, 1e-9));
    EXPECT_TRUE(matricesAgree(J.leftCols(n), rnea ? g.dtau_dq : g.dddq_dq, 1e-9));
    EXPECT_TRUE(matricesAgree(J.middleCols(n, n), rnea ? g.dtau_dv : g.dddq_dv, 1e-9));
    EXPECT_TRUE(matricesAgree(J.rightCols(n), rnea ? g.M : Eigen::MatrixXd(g.M.inverse()), 1e-9));
  }
}

INSTANTIATE_TEST_SUITE_P(Talos, PairedGolden,
                         ::testing::Values(PairedCase{"talos", "rnea"}, PairedCase{"talos", "aba"},
                                           PairedCase{"talos_ff", "rnea"}),
                         [](const ::testing::TestParamInfo<PairedCase>& info) {
                           return info.param.robot + "_" + info.param.fn;
                         });

}  // namespace
}  // namespace robodiff
