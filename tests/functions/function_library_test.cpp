// Generated function libraries end to end, through the C compiler: spec -> trace ->
// derivatives -> C -> .so -> LoadedLibrary. The compiled functions equal the
// interpreter (1e-12), the double reference (values; Jacobians and Hessians against
// central differences) and Pinocchio's golden derivatives; sparse blocks hold the dense
// entries; the batched entry point equals the single one bit for bit; split libraries
// equal unsplit ones. Failures: library_errors_test.cpp; the description JSON:
// library_description_test.cpp.
//
// Compile time, not run time, is what this file spends (gcc at O1 takes ~10 s per 15k
// operations, at O0 ~1 s): libraries are compiled at O0, except small ones at O1, where
// gcc with -march=native contracts a*b + c into FMAs, so that the interpreter and the
// batched entry point are also checked against optimised code; the largest (talos with
// a free-flyer, 225k operations) with tcc when it is installed. Each library lives in a
// temporary directory removed at exit; those used by several tests are built once
// (compiled_examples.hpp).
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>

#include <Eigen/LU>

#include <gtest/gtest.h>

#include "compiled_examples.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/model_function.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;
using testing::cached;
using testing::Compiled;
using testing::compile;
using testing::exampleSpec;
using testing::libraryArm7;
using testing::matricesAgree;
using testing::quadruped;
using testing::robot;
using testing::TempDir;

std::vector<Eigen::VectorXd> evaluateCompiled(const Compiled& c, const std::vector<Eigen::VectorXd>& runtime) {
  return evaluateBlocks(*c.function, c.definition(), runtime);
}

// The runtime inputs without the weights block (the function's own inputs).
std::vector<Eigen::VectorXd> libraryVariableInputs(const BuiltFunction& f, const std::vector<Eigen::VectorXd>& runtime) {
  std::vector<Eigen::VectorXd> v;
  for (std::size_t b = 0; b < f.definition.inputs.size(); ++b)
    if (f.definition.inputs[b].name != "weights") v.push_back(runtime[b]);
  return v;
}

// ---------------------------------------------------------------------------------------
// 1. Compiled == interpreted == reference.

struct SpecCase {
  std::string robot, spec, optimization;
};

void PrintTo(const SpecCase& c, std::ostream* os) { *os << c.robot << "/" << c.spec << "/" << c.optimization; }

std::vector<SpecCase> specCases() {
  return {
      {"arm7", "rnea_jacobian", "O0"},      {"arm7", "aba_jacobian", "O0"},      {"arm7", "rnea_hessian", "O0"},
      {"arm7", "crba", "O1"},               {"arm7", "fk", "O1"},                {"quadruped", "rnea_jacobian", "O0"},
      {"quadruped", "aba_jacobian", "O0"},  {"quadruped", "rnea_hessian", "O0"}, {"quadruped", "crba", "O0"},
  };
}

class CompiledExampleSpecs : public ::testing::TestWithParam<SpecCase> {};

TEST_P(CompiledExampleSpecs, CompiledEqualsInterpretedEqualsReference) {
  const Model& model = robot(GetParam().robot);
  const Compiled& c = cached(GetParam().robot, GetParam().spec, GetParam().optimization);
  const FunctionSpec& spec = c.spec;
  const BuiltFunction& f = c.built();
  ASSERT_EQ(f.outputs.size(), spec.outputs.size());
  ASSERT_EQ(c.function->descriptor().n_outputs, f.definition.outputs.size());
  codegen::Interpreter interpreter(*f.graph, f.definition);
  // Forward dynamics inverts M: rounding differences grow with its condition number.
  const double value_tolerance = spec.function == ModelFunction::Aba ? 1e-10 : 1e-12;

  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, spec, seed);
    const std::vector<Eigen::VectorXd> all = completeInputs(spec, libraryVariableInputs(f, runtime));
    const std::vector<Eigen::VectorXd> compiled = evaluateCompiled(c, runtime);
    const std::vector<Eigen::VectorXd> interpreted = evaluateBlocks(interpreter, f.definition, runtime);
    const Eigen::VectorXd value = referenceValue(model, spec, all);
    for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
      const OutputSpec& o = spec.outputs[k];
      const BuiltOutput& b = f.outputs[k];
      const codegen::OutputBlock& block = f.definition.outputs[k];
      SCOPED_TRACE(b.name);
      const bool hessian = o.kind == OutputKind::Hessian;
      const Eigen::MatrixXd got = blockMatrix(block, compiled[k], hessian);
      ASSERT_EQ(got.rows(), b.rows);
      ASSERT_EQ(got.cols(), b.cols);
      EXPECT_TRUE(matricesAgree(got, blockMatrix(block, interpreted[k], hessian), 1e-12)) << "compiled vs interpreted";
      if (o.kind == OutputKind::Value) {
        Eigen::MatrixXd expected(b.rows, b.cols);
        for (int r = 0, i = 0; r < b.rows; ++r)
          for (int col = 0; col < b.cols; ++col) expected(r, col) = value[i++];
        EXPECT_TRUE(matricesAgree(got, expected, value_tolerance)) << "compiled vs reference";
      } else if (o.kind == OutputKind::Jacobian) {
        EXPECT_TRUE(matricesAgree(got, finiteDifferenceJacobian(model, spec, all, o.wrt), 1e-5))
            << "compiled vs central differences";
      } else {
        const Eigen::VectorXd w =
            o.fixed_weights ? Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(
                                  o.fixed_weights->data(), static_cast<Eigen::Index>(o.fixed_weights->size())))
                            : Eigen::VectorXd(runtime.back());
        EXPECT_TRUE(matricesAgree(got, finiteDifferenceHessian(model, spec, all, w, o.wrt), 2e-5))
            << "compiled vs second central differences";
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(ProjectRobots, CompiledExampleSpecs, ::testing::ValuesIn(specCases()),
                         [](const ::testing::TestParamInfo<SpecCase>& info) {
                           return info.param.robot + "_" + info.param.spec + "_" + info.param.optimization;
                         });

// ---------------------------------------------------------------------------------------
// 2. Compiled against Pinocchio (../shared/golden).

class CompiledGolden : public ::testing::TestWithParam<std::string> {};

TEST_P(CompiledGolden, RneaAndAbaJacobiansMatchPinocchio) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  ASSERT_EQ(model.nq, golden.nq);
  ASSERT_EQ(model.nv, golden.nv);
  const int n = model.nv;
  // talos_ff's ABA Jacobian is 225k operations: 20 s with gcc at O0, under 1 s with tcc.
  LibraryOptions options;
  if (const std::optional<fs::path> tcc = testing::programInPath("tcc"); tcc && model.nv > 20) options.compiler.compiler = *tcc;
  for (const char* name : {"rnea_jacobian", "aba_jacobian"}) {
    SCOPED_TRACE(name);
    const std::unique_ptr<Compiled> c = compile(model, exampleSpec(name), options);
    SCOPED_TRACE("compiled by " + c->generated.compile.compiler);
    const bool rnea = c->spec.function == ModelFunction::Rnea;
    const codegen::FunctionDefinition& def = c->definition();
    ASSERT_EQ(def.outputs.size(), 2u);
    ASSERT_EQ(def.outputs[1].rows, static_cast<std::uint32_t>(n));
    ASSERT_EQ(def.outputs[1].cols, static_cast<std::uint32_t>(3 * n));
    for (std::size_t s : {std::size_t{0}, std::size_t{7}, std::size_t{13}, std::size_t{19}}) {
      if (s >= golden.samples.size()) continue;
      SCOPED_TRACE("sample " + std::to_string(s));
      const testing::GoldenSample& x = golden.samples[s];
      const std::vector<Eigen::VectorXd> out = evaluateCompiled(*c, {x.q, x.v, rnea ? x.a : x.tau});
      const Eigen::MatrixXd J = blockMatrix(def.outputs[1], out[1]);
      if (rnea) {
        EXPECT_TRUE(matricesAgree(out[0], x.tau, 1e-9));
        EXPECT_TRUE(matricesAgree(J.leftCols(n), x.dtau_dq, 1e-9)) << "dtau_dq";
        EXPECT_TRUE(matricesAgree(J.middleCols(n, n), x.dtau_dv, 1e-9)) << "dtau_dv";
        EXPECT_TRUE(matricesAgree(J.rightCols(n), x.M, 1e-9)) << "dtau_da = M";
      } else {
        EXPECT_TRUE(matricesAgree(out[0], x.ddq, 1e-9));
        EXPECT_TRUE(matricesAgree(J.leftCols(n), x.dddq_dq, 1e-9)) << "dddq_dq";
        EXPECT_TRUE(matricesAgree(J.middleCols(n, n), x.dddq_dv, 1e-9)) << "dddq_dv";
        EXPECT_TRUE(matricesAgree(J.rightCols(n), x.M.inverse(), 1e-9)) << "dddq_dtau = M^-1";
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Pinocchio, CompiledGolden, ::testing::Values("panda", "talos_ff"));

// ---------------------------------------------------------------------------------------
// 3. Sparse layouts hold exactly the dense entries.

// Entries of `dense` outside the CSR pattern of `block` (mirrored when symmetric_lower)
// that are not exactly zero.
int nonzerosOutsidePattern(const codegen::OutputBlock& block, const Eigen::MatrixXd& dense, bool symmetric_lower) {
  Eigen::MatrixXi in_pattern = Eigen::MatrixXi::Zero(block.rows, block.cols);
  for (std::uint32_t r = 0; r < block.rows; ++r)
    for (std::uint32_t k = block.row_ptr[r]; k < block.row_ptr[r + 1]; ++k) {
      in_pattern(r, block.col_idx[k]) = 1;
      if (symmetric_lower) in_pattern(block.col_idx[k], r) = 1;
    }
  int count = 0;
  for (Eigen::Index r = 0; r < dense.rows(); ++r)
    for (Eigen::Index col = 0; col < dense.cols(); ++col)
      if (!in_pattern(r, col) && dense(r, col) != 0.0) ++count;
  return count;
}

TEST(SparseLayout, SparseJacobianEqualsTheDenseOneOnTheQuadruped) {
  const Model& model = quadruped();
  const Compiled& dense = cached("quadruped", "rnea_jacobian");
  const Compiled& sparse = cached("quadruped", "rnea_jacobian_sparse");
  const codegen::OutputBlock& dblock = dense.definition().outputs[1];
  const codegen::OutputBlock& sblock = sparse.definition().outputs[1];
  ASSERT_EQ(sblock.kind, codegen::OutputKind::Sparse);
  ASSERT_EQ(dblock.kind, codegen::OutputKind::Dense);
  ASSERT_EQ(sblock.rows, dblock.rows);
  ASSERT_EQ(sblock.cols, dblock.cols);
  // A tree: a leg's torques do not depend on another leg's joints.
  EXPECT_LT(sblock.size(), sblock.rows * sblock.cols);
  EXPECT_EQ(sparse.function->descriptor().outputs[1].nnz, sblock.size());
  std::cout << "quadruped d tau/d(q, v, a): " << sblock.size() << " of " << sblock.rows * sblock.cols
            << " entries structurally nonzero\n";
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, dense.spec, seed);
    const std::vector<Eigen::VectorXd> d = evaluateCompiled(dense, runtime), s = evaluateCompiled(sparse, runtime);
    EXPECT_TRUE(matricesAgree(s[0], d[0], 1e-12)) << "values";
    const Eigen::MatrixXd D = blockMatrix(dblock, d[1]);
    EXPECT_TRUE(matricesAgree(blockMatrix(sblock, s[1]), D, 1e-12));
    EXPECT_EQ(nonzerosOutsidePattern(sblock, D, false), 0) << "the dense Jacobian is 0 outside the CSR pattern";
  }
}

TEST(SparseLayout, SparseHessianEqualsTheDenseOneOnTheQuadruped) {
  const Model& model = quadruped();
  const Compiled& dense = cached("quadruped", "rnea_hessian");
  const Compiled& sparse = cached("quadruped", "rnea_hessian_sparse");
  ASSERT_EQ(dense.definition().outputs.size(), 3u);
  ASSERT_EQ(sparse.definition().outputs.size(), 3u);
  const codegen::OutputBlock& dblock = dense.definition().outputs[2];
  const codegen::OutputBlock& sblock = sparse.definition().outputs[2];
  ASSERT_EQ(dblock.kind, codegen::OutputKind::Dense);
  ASSERT_EQ(sblock.kind, codegen::OutputKind::Sparse);
  const std::uint32_t n = dblock.rows;
  ASSERT_EQ(n, static_cast<std::uint32_t>(model.nv));
  // Lower triangle only, and fewer still: the legs do not couple.
  for (std::uint32_t r = 0; r < n; ++r)
    for (std::uint32_t k = sblock.row_ptr[r]; k < sblock.row_ptr[r + 1]; ++k) ASSERT_LE(sblock.col_idx[k], r);
  EXPECT_LT(sblock.size(), n * (n + 1) / 2);
  std::cout << "quadruped sum_i w_i d2 tau_i/dq2: " << sblock.size() << " of " << n * (n + 1) / 2
            << " lower-triangle entries structurally nonzero\n";
  // Same input blocks (q, v, a, weights).
  ASSERT_EQ(sparse.definition().inputs.size(), dense.definition().inputs.size());
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, dense.spec, seed);
    const std::vector<Eigen::VectorXd> d = evaluateCompiled(dense, runtime), s = evaluateCompiled(sparse, runtime);
    const Eigen::MatrixXd D = blockMatrix(dblock, d[2]);
    EXPECT_TRUE(matricesAgree(D, D.transpose(), 0.0)) << "the dense Hessian is symmetric";
    EXPECT_TRUE(matricesAgree(blockMatrix(sblock, s[2], true), D, 1e-12));
    EXPECT_EQ(nonzerosOutsidePattern(sblock, D, true), 0) << "the dense Hessian is 0 outside the CSR pattern";
  }
}

// ---------------------------------------------------------------------------------------
// 4. The batched entry point equals the single one, bit for bit.

// The quadruped's RNEA Jacobian (the case asked for), and the arm's FK at O1, where
// gcc contracts into FMAs in both the scalar and the SIMD body.
class BatchedEvaluation : public ::testing::TestWithParam<SpecCase> {};

TEST_P(BatchedEvaluation, EqualsSingleEvaluationsBitForBit) {
  const Model& model = robot(GetParam().robot);
  const Compiled& c = cached(GetParam().robot, GetParam().spec, GetParam().optimization);
  const codegen::CompiledFunction& f = *c.function;
  const codegen::FunctionDefinition& def = c.definition();
  std::cout << "batch width " << f.batchWidth() << ", batch work " << f.batchWorkSize() << " doubles\n";
  const double sentinel = std::numeric_limits<double>::quiet_NaN();
  for (std::uint64_t n : {1u, 8u, 13u}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    // Knot k of block b at in[b] + k * size; one extra knot of output that must stay untouched.
    std::vector<std::vector<Eigen::VectorXd>> knots;
    std::vector<std::vector<double>> in(def.inputs.size()), out(def.outputs.size());
    for (std::uint64_t k = 0; k < n; ++k) {
      knots.push_back(randomRuntimeInputs(model, c.spec, 1000 * n + k));
      for (std::size_t b = 0; b < in.size(); ++b) in[b].insert(in[b].end(), knots[k][b].begin(), knots[k][b].end());
    }
    for (std::size_t j = 0; j < out.size(); ++j) out[j].assign((n + 1) * def.outputs[j].size(), sentinel);
    std::vector<const double*> in_ptr;
    std::vector<double*> out_ptr;
    for (const auto& v : in) in_ptr.push_back(v.data());
    for (auto& v : out) out_ptr.push_back(v.data());
    std::vector<double> work(f.batchWorkSize());
    f.evaluateBatch(n, in_ptr.data(), out_ptr.data(), work.empty() ? nullptr : work.data());

    std::size_t differing = 0, compared = 0;
    double worst = 0;
    for (std::uint64_t k = 0; k < n; ++k) {
      const std::vector<Eigen::VectorXd> single = evaluateCompiled(c, knots[k]);
      for (std::size_t j = 0; j < out.size(); ++j) {
        const std::size_t size = def.outputs[j].size();
        for (std::size_t i = 0; i < size; ++i) {
          const double batched = out[j][k * size + i], one = single[j][static_cast<Eigen::Index>(i)];
          ++compared;
          if (std::memcmp(&batched, &one, sizeof(double)) != 0) {
            ++differing;
            worst = std::max(worst, std::abs(batched - one) / std::max(std::abs(one), 1e-12));
          }
        }
      }
    }
    EXPECT_EQ(differing, 0u) << "of " << compared << " doubles differ from single evaluation; largest relative "
                             << "difference " << worst;
    for (std::size_t j = 0; j < out.size(); ++j) {
      const std::size_t size = def.outputs[j].size();
      for (std::size_t i = 0; i < size; ++i)
        ASSERT_TRUE(std::isnan(out[j][n * size + i])) << "written past knot n - 1 in block " << def.outputs[j].name;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Knots, BatchedEvaluation,
                         ::testing::Values(SpecCase{"quadruped", "rnea_jacobian", "O0"}, SpecCase{"arm7", "fk", "O1"}),
                         [](const ::testing::TestParamInfo<SpecCase>& info) {
                           return info.param.robot + "_" + info.param.spec + "_" + info.param.optimization;
                         });

// ---------------------------------------------------------------------------------------
// 5. A split library computes what the unsplit one does.

TEST(SplitLibrary, ManyPartsGiveTheSameValues) {
  const Model& model = libraryArm7();
  const FunctionSpec spec = exampleSpec("rnea_jacobian");
  LibraryOptions split, whole;
  split.codegen.split_threshold = 500;
  whole.codegen.split_threshold = 0;
  const std::unique_ptr<Compiled> a = compile(model, spec, split), b = compile(model, spec, whole);
  EXPECT_GT(a->generated.info.parts, 1u);
  EXPECT_EQ(b->generated.info.parts, 1u);
  EXPECT_GE(a->generated.compile.commands.size(), a->generated.info.parts + 1u)
      << "the parts are compiled separately, then linked";
  std::cout << "rnea_jacobian on arm7: " << a->generated.info.operations << " operations, "
            << a->generated.info.parts << " parts at split_threshold 500, " << a->generated.info.transfer_slots
            << " transfer slots\n";
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, spec, seed);
    const std::vector<Eigen::VectorXd> x = evaluateCompiled(*a, runtime), y = evaluateCompiled(*b, runtime);
    ASSERT_EQ(x.size(), y.size());
    for (std::size_t k = 0; k < x.size(); ++k) EXPECT_TRUE(matricesAgree(x[k], y[k], 1e-12)) << "block " << k;
  }
}

// The quadruped's legs run the same recursion: its mass matrix computes twin operations
// in lane pairs, and still what the reference computes (its RNEA value pairs under 30%
// of its operations and keeps none). A derivative function is seeded at twins only; the
// quadruped's legs are not mirror images, and its RNEA Jacobian finds none (Talos's
// paired Jacobians: lane_pairs_golden_test.cpp).
TEST(LanePairs, TheQuadrupedsMassMatrixIsPairedAndItsJacobianSeededAtTwinsOnly) {
  const Model& model = quadruped();
  FunctionSpec spec = parseFunctionSpec(R"({"function": "crba", "outputs": [{"kind": "value"}]})");
  spec.build.optimization = "O2";
  const std::unique_ptr<Compiled> c = compile(model, spec);
  std::cout << "quadruped crba value: " << c->generated.info.lane_pairs << " pairs in "
            << c->generated.info.operations << " operations\n";
  EXPECT_EQ(c->definition().lane_pairs, codegen::LanePairSeeds::TwinsAndColumns);
  EXPECT_GE(2 * c->generated.info.lane_pairs, c->generated.info.operations * 3 / 10);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, spec, seed);
    const Eigen::VectorXd value = evaluateCompiled(*c, runtime)[0];
    const Eigen::VectorXd expected = referenceValue(model, spec, completeInputs(spec, runtime));
    EXPECT_TRUE(matricesAgree(value, expected, 1e-12)) << "seed " << seed;
  }
  EXPECT_EQ(cached("quadruped", "rnea_jacobian").definition().lane_pairs, codegen::LanePairSeeds::Twins);
}

}  // namespace
}  // namespace robodiff
