// A generated function library's description JSON agrees with its definition and with
// the library's own descriptor: names, model, spec, inputs, outputs (shapes, layouts,
// sparsity patterns), and the build's figures and flags.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "compiled_examples.hpp"
#include "robodiff/model/canonical.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::cached;
using testing::Compiled;
using testing::libraryArm7;
using testing::quadruped;

std::vector<std::uint32_t> array(const std::uint32_t* p, std::size_t n) {
  return p ? std::vector<std::uint32_t>(p, p + n) : std::vector<std::uint32_t>{};
}

void checkDescription(const Model& model, const Compiled& c) {
  const codegen::FunctionDefinition& def = c.definition();
  const BuiltFunction& built = c.built();
  const robodiff_function_desc& desc = c.function->descriptor();
  ASSERT_EQ(c.generated.description, c.dir.path() / "out" / (def.name + ".json"));
  ASSERT_TRUE(fs::exists(c.generated.description));
  const json d = json::parse(testing::readFile(c.generated.description));

  EXPECT_EQ(d.at("name"), def.name);
  EXPECT_EQ(std::string(desc.name), def.name);
  EXPECT_EQ(d.at("model").at("name"), model.name);
  EXPECT_EQ(d.at("model").at("nq"), model.nq);
  EXPECT_EQ(d.at("model").at("nv"), model.nv);
  EXPECT_EQ(d.at("model").at("hash"), canonicalHash(model));
  EXPECT_EQ(d.at("model").at("hash").get<std::string>().size(), 64u) << "SHA-256 in hex";
  EXPECT_EQ(d.at("spec"), json::parse(normalizedSpecJson(c.spec)));

  const json& inputs = d.at("inputs");
  ASSERT_EQ(inputs.size(), def.inputs.size());
  ASSERT_EQ(desc.n_inputs, def.inputs.size());
  for (std::size_t b = 0; b < def.inputs.size(); ++b) {
    SCOPED_TRACE("input " + def.inputs[b].name);
    EXPECT_EQ(inputs[b].at("name"), def.inputs[b].name);
    EXPECT_EQ(inputs[b].at("size"), def.inputs[b].size);
    EXPECT_EQ(std::string(desc.inputs[b].name), def.inputs[b].name);
    EXPECT_EQ(desc.inputs[b].size, def.inputs[b].size);
  }
  // The runtime inputs: q (nq), v, a (nv), and weights (nv) when the Hessian takes them.
  EXPECT_EQ(def.inputs.at(0).name, "q");
  EXPECT_EQ(def.inputs.at(0).size, static_cast<std::uint32_t>(model.nq));

  const json& outputs = d.at("outputs");
  ASSERT_EQ(outputs.size(), def.outputs.size());
  ASSERT_EQ(desc.n_outputs, def.outputs.size());
  for (std::size_t k = 0; k < def.outputs.size(); ++k) {
    const codegen::OutputBlock& block = def.outputs[k];
    const BuiltOutput& b = built.outputs[k];
    const robodiff_output_desc& o = desc.outputs[k];
    const json& j = outputs[k];
    SCOPED_TRACE("output " + block.name);
    EXPECT_EQ(j.at("name"), block.name);
    EXPECT_EQ(std::string(o.name), block.name);
    EXPECT_EQ(j.at("kind"), toString(b.kind));
    EXPECT_EQ(j.at("rows"), block.rows);
    EXPECT_EQ(j.at("cols"), block.cols);
    EXPECT_EQ(j.at("nnz"), block.size());
    EXPECT_EQ(o.rows, block.rows);
    EXPECT_EQ(o.cols, block.cols);
    EXPECT_EQ(o.nnz, block.size());
    EXPECT_EQ(b.nnz, block.size());
    if (b.kind != OutputKind::Value) {
      EXPECT_EQ(j.at("wrt"), b.wrt);
    }
    if (block.kind == codegen::OutputKind::Sparse) {
      EXPECT_EQ(j.at("layout"), "sparse");
      EXPECT_EQ(o.kind, ROBODIFF_OUTPUT_SPARSE);
      const std::vector<std::uint32_t> row_ptr = array(o.row_ptr, o.rows + 1), col_idx = array(o.col_idx, o.nnz);
      EXPECT_EQ(j.at("row_ptr").get<std::vector<std::uint32_t>>(), row_ptr);
      EXPECT_EQ(j.at("col_idx").get<std::vector<std::uint32_t>>(), col_idx);
      EXPECT_EQ(row_ptr, block.row_ptr);
      EXPECT_EQ(col_idx, block.col_idx);
      EXPECT_EQ(row_ptr.back(), o.nnz);
      if (b.kind == OutputKind::Hessian) {
        EXPECT_EQ(j.at("triangle"), "lower triangle");
      }
    } else {
      EXPECT_EQ(j.at("layout"), "dense");
      EXPECT_EQ(o.kind, ROBODIFF_OUTPUT_DENSE);
      EXPECT_EQ(o.row_ptr, nullptr);
      EXPECT_EQ(o.col_idx, nullptr);
      EXPECT_EQ(o.nnz, o.rows * o.cols);
      EXPECT_FALSE(j.contains("row_ptr"));
      EXPECT_FALSE(j.contains("col_idx"));
      if (b.kind == OutputKind::Hessian) {
        EXPECT_EQ(j.at("triangle"), "full symmetric matrix");
      }
    }
  }

  const json& build = d.at("build");
  for (const char* seconds : {"trace_seconds", "differentiate_seconds", "assemble_seconds", "emit_seconds"}) {
    ASSERT_TRUE(build.at(seconds).is_number()) << seconds;
    EXPECT_GE(build.at(seconds).get<double>(), 0.0) << seconds;
  }
  EXPECT_GT(build.at("trace_seconds").get<double>(), 0.0);
  EXPECT_GT(build.at("compile_seconds").get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(build.at("compile_seconds").get<double>(), c.generated.compile.seconds);
  EXPECT_EQ(build.at("operations"), c.generated.info.operations);
  EXPECT_GT(build.at("operations").get<std::uint32_t>(), 0u);
  EXPECT_EQ(build.at("parts"), c.generated.info.parts);
  EXPECT_EQ(build.at("trace_nodes"), built.trace_nodes);
  EXPECT_EQ(build.at("function_nodes"), built.graph->size());
  EXPECT_EQ(build.at("library"), c.generated.library.filename().string());
  EXPECT_EQ(build.at("library_bytes"), fs::file_size(c.generated.library));
  EXPECT_EQ(build.at("flags"), c.generated.compile.flags);
  EXPECT_NE(std::find(c.generated.compile.flags.begin(), c.generated.compile.flags.end(),
                      "-" + c.spec.build.optimization),
            c.generated.compile.flags.end())
      << "the spec's build.optimization reaches the compiler";
  EXPECT_EQ(d.at("method"), built.method);
}

TEST(LibraryDescription, SparseJacobianDescriptionAgreesWithTheDescriptor) {
  checkDescription(quadruped(), cached("quadruped", "rnea_jacobian_sparse"));
}

TEST(LibraryDescription, SparseHessianDescriptionAgreesWithTheDescriptor) {
  checkDescription(quadruped(), cached("quadruped", "rnea_hessian_sparse"));
}

TEST(LibraryDescription, DenseDescriptionAgreesWithTheDescriptor) {
  checkDescription(libraryArm7(), cached("arm7", "rnea_hessian"));
}

}  // namespace
}  // namespace robodiff
