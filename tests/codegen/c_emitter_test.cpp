// The generated C source: what is in it and what is not (values are checked by
// compiled_function_test.cpp).
#include "robodiff/codegen/c_emitter.hpp"

#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <regex>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;

const std::string& mainSource(const GeneratedLibrary& lib) { return lib.sources.at(0).text; }

// The body of the scalar single-point entry point of `name` (unsplit functions).
std::string scalarBody(const GeneratedLibrary& lib, const std::string& name) {
  const std::string& s = mainSource(lib);
  const auto begin = s.find("static void rd_" + name + "_eval(");
  const auto end = s.find("\n}\n", begin);
  return s.substr(begin, end - begin);
}

TEST(CDoubleLiteral, ReadsBackExactly) {
  EXPECT_EQ(cDoubleLiteral(0.1), "0.1");
  EXPECT_EQ(cDoubleLiteral(2.0), "2.0");
  EXPECT_EQ(cDoubleLiteral(-0.0), "-0.0");
  EXPECT_EQ(cDoubleLiteral(1e300), "1e+300");
  EXPECT_EQ(cDoubleLiteral(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(cDoubleLiteral(std::numeric_limits<double>::infinity()), "INFINITY");
  std::mt19937_64 rng(7);
  for (int i = 0; i < 2000; ++i) {
    double x;
    std::uint64_t bits = rng();
    std::memcpy(&x, &bits, sizeof x);
    if (!std::isfinite(x)) continue;
    const std::string lit = cDoubleLiteral(x);
    EXPECT_EQ(std::strtod(lit.c_str(), nullptr), x) << lit;
    EXPECT_NE(lit.find_first_of(".e"), std::string::npos) << lit << " would be an integer in C";
  }
}

TEST(CEmitter, SinAndCosOfOneArgumentComeFromOneSincos) {
  Graph g;
  NodeId q = g.input(0);
  NodeId s = g.unary(Op::Sin, q), c = g.unary(Op::Cos, q);
  NodeId other = g.unary(Op::Sin, g.input(1));  // no partner: a plain sin
  FunctionDefinition f{"rot", {{"q", 2}}, {OutputBlock::dense("R", 2, 2, {c, g.unary(Op::Neg, s), s, other})}};
  auto lib = generateLibrary(g, {f});
  const std::string body = scalarBody(lib, "rot");
  EXPECT_EQ(countOf(body, "rd_sincos1("), 1u) << body;  // the inline kernel (sincos_kernel.h)
  EXPECT_EQ(countOf(body, "cos("), 0u) << body;
  EXPECT_EQ(countOf(body, " sin("), 1u) << body;
  EXPECT_EQ(lib.functions.at(0).sincos_pairs, 1u);
  EXPECT_NE(mainSource(lib).find("rd_sincos("), std::string::npos);  // the batched variant too
}

TEST(CEmitter, NegationsFoldIntoTheirConsumers) {
  Graph g;
  NodeId x = g.input(0), y = g.input(1), z = g.input(2);
  NodeId xy = g.binary(Op::Mul, x, y);
  NodeId e1 = g.binary(Op::Div, g.unary(Op::Sin, x), g.unary(Op::Neg, g.unary(Op::Exp, z)));  // a / -b
  NodeId e2 = g.binary(Op::Add, g.unary(Op::Neg, xy), g.unary(Op::Cos, z));                   // -a + b
  NodeId e3 = g.unary(Op::Neg, g.binary(Op::Mul, e1, e2));                                     // output -(...)
  NodeId e4 = g.binary(Op::Add, g.unary(Op::Tanh, y), g.constant(-2.5));                       // b + (-2.5)
  FunctionDefinition f{"folding", {{"x", 3}}, {OutputBlock::dense("out", 4, 1, {e1, e2, e3, e4})}};
  auto lib = generateLibrary(g, {f});
  const std::string body = scalarBody(lib, "folding");
  for (const char* bad : {"* -1", "-1.0 *", "+ -", "- -", "(-1"})
    EXPECT_EQ(body.find(bad), std::string::npos) << "'" << bad << "' in\n" << body;
  EXPECT_NE(body.find(" - 2.5"), std::string::npos) << body;
  EXPECT_TRUE(std::regex_search(body, std::regex(R"(o0\[0\] = -t\d+;)"))) << body;  // a negated output
  EXPECT_TRUE(std::regex_search(body, std::regex(R"(= t\d+ - t\d+;)"))) << body;       // -a + b
}

TEST(CEmitter, RandomGraphsNeverMultiplyByMinusOneOrAddANegation) {
  Graph g;
  std::vector<FunctionDefinition> fs;
  for (std::uint32_t seed = 1; seed <= 4; ++seed) fs.push_back(randomFunction(g, "f" + std::to_string(seed), seed, 150));
  auto lib = generateLibrary(g, fs);
  const std::string& s = mainSource(lib);
  for (const char* bad : {"* -1.0", "-1.0 *", "+ -", "- -"}) EXPECT_EQ(s.find(bad), std::string::npos) << bad;
}

TEST(CEmitter, OnlyWhatTheOutputsNeedIsComputed) {
  Graph g;
  NodeId x = g.input(0);
  NodeId unused = g.unary(Op::Exp, g.binary(Op::Mul, x, g.constant(7.25)));
  (void)unused;
  NodeId used = g.unary(Op::Sqrt, g.binary(Op::Add, x, g.constant(3.0)));
  FunctionDefinition f{"f", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {used})}};
  auto lib = generateLibrary(g, {f});
  const std::string body = scalarBody(lib, "f");
  EXPECT_EQ(body.find("exp("), std::string::npos) << body;
  EXPECT_EQ(body.find("7.25"), std::string::npos) << body;
  EXPECT_EQ(lib.functions[0].operations, 2u);
}

TEST(CEmitter, ConstantAndInputOutputsAreWrittenDirectly) {
  Graph g;
  NodeId x = g.input(0);
  FunctionDefinition f{"f", {{"x", 2}}, {OutputBlock::dense("y", 1, 4, {g.constant(0.1), x, g.unary(Op::Neg, g.input(1)),
                                                                        g.unary(Op::Sin, x)})}};
  auto lib = generateLibrary(g, {f});
  const std::string body = scalarBody(lib, "f");
  // Stored one by one, or named and stored as one group of four (output_groups.hpp).
  for (const char* copy : {R"((o0\[0\]|rd_o0_0) = 0\.1;)", R"((o0\[1\]|rd_o0_1) = i0\[0\];)",
                           R"((o0\[2\]|rd_o0_2) = -i0\[1\];)"})
    EXPECT_TRUE(std::regex_search(body, std::regex(copy))) << copy << " in\n" << body;
}

TEST(CEmitter, TemporariesAreReusedByLiveness) {
  // A long chain: each value dies at its only use, so a few locals suffice.
  Graph g;
  NodeId x = g.input(0), acc = x;
  for (int i = 0; i < 300; ++i)
    acc = g.unary(i % 2 ? Op::Sin : Op::Tanh, g.binary(Op::Add, acc, g.constant(0.01 * (i + 1))));
  FunctionDefinition f{"chain", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {acc})}};
  auto reused = generateLibrary(g, {f});
  EXPECT_EQ(reused.functions[0].operations, 600u);
  EXPECT_LE(reused.functions[0].max_locals, 2u);
  CodegenOptions fresh;
  fresh.reuse_temporaries = false;
  EXPECT_GE(generateLibrary(g, {f}, fresh).functions[0].max_locals, 600u);
  // Declared where first needed, then reassigned.
  const std::string body = scalarBody(reused, "chain");
  EXPECT_EQ(countOf(body, "double t0 ="), 1u) << body.substr(0, 400);
}

TEST(CEmitter, SplitsLargeFunctionsIntoTranslationUnits) {
  Graph g;
  FunctionDefinition f = chainFunction(g, "fk", 6);
  CodegenOptions options;
  options.split_threshold = 40;
  auto lib = generateLibrary(g, {f}, options);
  const auto& info = lib.functions.at(0);
  EXPECT_GE(info.parts, 2u);
  EXPECT_EQ(lib.sources.size(), 1 + info.parts);
  EXPECT_GT(info.transfer_slots, 0u);
  for (std::size_t p = 1; p < lib.sources.size(); ++p) {
    EXPECT_NE(lib.sources[p].text.find("rd_fk_p" + std::to_string(p - 1) + "("), std::string::npos);
    EXPECT_NE(lib.sources[p].text.find("w["), std::string::npos);
  }
  EXPECT_EQ(generateLibrary(g, {f}).sources.size(), 1u);
}

TEST(CEmitter, DescribesItselfInTheSource) {
  Graph g;
  FunctionDefinition f = triangularFunction(g, "tri", 3);
  auto lib = generateLibrary(g, {f});
  const std::string& s = mainSource(lib);
  EXPECT_NE(s.find("#include \"robodiff/codegen/abi.h\""), std::string::npos);
  EXPECT_NE(s.find("robodiff_library ="), std::string::npos);
  EXPECT_NE(s.find("ROBODIFF_OUTPUT_SPARSE"), std::string::npos);
  EXPECT_NE(s.find(kGeneratorVersion), std::string::npos);
  EXPECT_NE(s.find("#include \"robodiff/codegen/sincos_kernel.h\""), std::string::npos);
  ASSERT_EQ(lib.headers.size(), 2u);
  EXPECT_EQ(lib.headers[0].path, "robodiff/codegen/abi.h");
  EXPECT_NE(lib.headers[0].text.find("ROBODIFF_ABI_VERSION"), std::string::npos);
  EXPECT_EQ(lib.headers[1].path, "robodiff/codegen/sincos_kernel.h");
  EXPECT_NE(lib.headers[1].text.find("rd_sincos1"), std::string::npos);
}

// The batched chunk clears large output blocks before scattering into them (the
// memset claims their cache lines); the single-knot code and small blocks do not.
TEST(CEmitter, TheBatchedChunkClaimsLargeOutputBlocks) {
  Graph g;
  FunctionDefinition f = triangularFunction(g, "tri", 24);  // J: 300 values, g: 24
  const GeneratedLibrary lib = generateLibrary(g, {f});
  const std::string& s = mainSource(lib);
  const std::size_t chunk = s.find("static void rd_tri_chunk(");
  ASSERT_NE(chunk, std::string::npos);
  const std::string vector_body = s.substr(chunk, s.find("\n}\n", chunk) - chunk);
  EXPECT_EQ(countOf(vector_body, "memset(o0, 0, RD_W * 300 * sizeof(double)); /* claim the lines */"), 1u) << vector_body;
  EXPECT_EQ(countOf(vector_body, "memset(o1"), 0u);
  EXPECT_EQ(countOf(scalarBody(lib, "tri"), "memset"), 0u);
}

TEST(CEmitter, RejectsBadDefinitions) {
  Graph g;
  NodeId x = g.input(0);
  FunctionDefinition bad_name{"not a name", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {x})}};
  EXPECT_THROW(generateLibrary(g, {bad_name}), std::invalid_argument);
  FunctionDefinition bad_shape{"f", {{"x", 1}}, {OutputBlock::dense("y", 2, 2, {x})}};
  EXPECT_THROW(generateLibrary(g, {bad_shape}), std::invalid_argument);
  FunctionDefinition missing_input{"f", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {g.input(3)})}};
  try {
    generateLibrary(g, {missing_input});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("input 3"), std::string::npos) << e.what();
  }
  FunctionDefinition bad_csr{"f", {{"x", 1}}, {OutputBlock::sparse("y", 2, 2, {0, 1, 1}, {5}, {x})}};
  EXPECT_THROW(generateLibrary(g, {bad_csr}), std::invalid_argument);
  FunctionDefinition ok{"f", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {x})}};
  EXPECT_THROW(generateLibrary(g, {ok, ok}), std::invalid_argument);  // duplicate name
}

}  // namespace
}  // namespace robodiff::codegen
