// A spec's `"build": {"batch": false}`: the single-knot code alone (no SIMD batched
// chunk), what it normalises to, and that batched evaluation still computes what single
// calls compute.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;

FunctionSpec rneaJacobianBuiltWith(const std::string& build_json) {
  return parseFunctionSpec(R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}],
                               "build": )" + build_json + "}",
                           "batch.json");
}

std::string batchRefusalOf(const std::string& build_json) {
  try {
    rneaJacobianBuiltWith(build_json);
  } catch (const SpecError& e) {
    return e.what();
  }
  return "accepted";
}

const Model& batchTestQuadruped() {
  static const Model m =
      loadUrdfFile((testing::sourceDir() / "examples/robots/quadruped.urdf").string(), RootJoint::FreeFlyer);
  return m;
}

std::string readWholeFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Every generated C file of a library (its src/ folder), concatenated.
std::string generatedSources(const fs::path& out_dir) {
  std::string all;
  for (const auto& e : fs::recursive_directory_iterator(out_dir / "src"))
    if (e.path().extension() == ".c") all += readWholeFile(e.path());
  return all;
}

TEST(BuildBatch, FalseIsKeptInTheNormalisedSpecAndTrueIsTheDefault) {
  const FunctionSpec unbatched = rneaJacobianBuiltWith(R"({"batch": false})");
  EXPECT_FALSE(unbatched.build.batch);
  EXPECT_TRUE(rneaJacobianBuiltWith("{}").build.batch);
  EXPECT_NE(normalizedSpecJson(unbatched).find(R"("batch":false)"), std::string::npos) << normalizedSpecJson(unbatched);
  EXPECT_EQ(normalizedSpecJson(parseFunctionSpec(normalizedSpecJson(unbatched))), normalizedSpecJson(unbatched));
  // The default keeps the JSON (and so the cache key) specs had before the option.
  EXPECT_EQ(normalizedSpecJson(rneaJacobianBuiltWith(R"({"batch": true})")), normalizedSpecJson(rneaJacobianBuiltWith("{}")));
  EXPECT_EQ(normalizedSpecJson(rneaJacobianBuiltWith("{}")).find("batch"), std::string::npos);
}

TEST(BuildBatch, ANonBooleanIsRefusedByName) {
  const std::string refusal = batchRefusalOf(R"({"batch": "no"})");
  EXPECT_NE(refusal.find("build.batch"), std::string::npos) << refusal;
  EXPECT_NE(refusal.find("not true or false"), std::string::npos) << refusal;
}

// evaluateBatch over `knots` random knots equals one evaluate per knot, bit for bit.
void expectBatchEqualsSingleCalls(const codegen::CompiledFunction& f, const codegen::FunctionDefinition& def,
                                  std::uint64_t knots) {
  std::vector<std::vector<double>> in(def.inputs.size()), out(def.outputs.size());
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (std::size_t b = 0; b < in.size(); ++b)
    for (std::uint64_t i = 0; i < knots * def.inputs[b].size; ++i) in[b].push_back(uniform(rng));
  for (std::size_t b = 0; b < out.size(); ++b) out[b].assign(knots * def.outputs[b].size(), std::nan(""));
  std::vector<const double*> in_ptr;
  std::vector<double*> out_ptr;
  for (const auto& v : in) in_ptr.push_back(v.data());
  for (auto& v : out) out_ptr.push_back(v.data());
  std::vector<double> work(std::max<std::size_t>(f.batchWorkSize(), f.workSize()) + 1);
  f.evaluateBatch(knots, in_ptr.data(), out_ptr.data(), work.data());
  for (std::uint64_t k = 0; k < knots; ++k) {
    std::vector<const double*> one_in;
    std::vector<std::vector<double>> one(def.outputs.size());
    std::vector<double*> one_ptr;
    for (std::size_t b = 0; b < in.size(); ++b) one_in.push_back(in[b].data() + k * def.inputs[b].size);
    for (std::size_t b = 0; b < out.size(); ++b) {
      one[b].assign(def.outputs[b].size(), std::nan(""));
      one_ptr.push_back(one[b].data());
    }
    f.evaluate(one_in.data(), one_ptr.data(), work.data());
    for (std::size_t b = 0; b < out.size(); ++b)
      for (std::size_t i = 0; i < one[b].size(); ++i) {
        const double batch = out[b][k * one[b].size() + i];
        ASSERT_FALSE(std::isnan(batch)) << "knot " << k << " block " << b << " entry " << i;
        ASSERT_EQ(std::memcmp(&batch, &one[b][i], sizeof batch), 0) << "knot " << k << " block " << b << " entry " << i;
      }
  }
}

TEST(BuildBatch, TheUnbatchedLibraryHasNoSimdChunkAndBatchesStillEqualSingleCalls) {
  testing::TempDir dir;
  const FunctionSpec batched = rneaJacobianBuiltWith(R"({"optimization": "O1"})");
  const FunctionSpec unbatched = rneaJacobianBuiltWith(R"({"optimization": "O1", "batch": false})");
  const GeneratedFunctionLibrary with = generateFunctionLibrary(batchTestQuadruped(), batched, dir.path() / "with");
  const GeneratedFunctionLibrary without = generateFunctionLibrary(batchTestQuadruped(), unbatched, dir.path() / "without");
  const std::string with_c = generatedSources(dir.path() / "with"), without_c = generatedSources(dir.path() / "without");
  EXPECT_NE(with_c.find("_chunk(const double"), std::string::npos);  // the SIMD chunk's definition
  EXPECT_EQ(without_c.find("_chunk(const double"), std::string::npos);
  EXPECT_NE(without_c.find("#define RD_VECTOR 0"), std::string::npos);
  EXPECT_LT(without.source_bytes * 10, with.source_bytes * 7) << "the batched code is most of a library's source";

  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(without.library);
  const codegen::CompiledFunction f = library.function(without.built.definition.name);
  EXPECT_EQ(f.batchWidth(), 1u);
  expectBatchEqualsSingleCalls(f, without.built.definition, 5);
}

}  // namespace
}  // namespace robodiff
