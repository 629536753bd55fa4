// The text every generated translation unit starts with: under gcc it declares the C
// library functions it calls instead of reading <math.h> and <string.h> (about 20 ms of
// each compile); every compiler still gets the functions and the non-finite constants.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
namespace fs = std::filesystem;

// y = [sin x, sqrt(x + 3), +inf, -inf, NaN, x * +inf]: libm calls and the constants
// the emitter writes as INFINITY and NAN.
FunctionDefinition nonFiniteFunction(Graph& g) {
  const NodeId x = g.input(0);
  const double inf = std::numeric_limits<double>::infinity();
  return FunctionDefinition{"f",
                            {{"x", 1}},
                            {OutputBlock::dense("y", 1, 6,
                                                {g.unary(Op::Sin, x), g.unary(Op::Sqrt, g.binary(Op::Add, x, g.constant(3.0))),
                                                 g.constant(inf), g.constant(-inf),
                                                 g.constant(std::numeric_limits<double>::quiet_NaN()),
                                                 g.binary(Op::Mul, x, g.constant(inf))})}};
}

void writeAll(const GeneratedLibrary& lib, const fs::path& dir) {
  for (const auto* files : {&lib.sources, &lib.headers})
    for (const SourceFile& file : *files) {
      fs::create_directories((dir / file.path).parent_path());
      std::ofstream(dir / file.path) << file.text;
    }
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CPrologue, GccReadsNeitherMathHNorStringH) {
  Graph g;
  const GeneratedLibrary lib = generateLibrary(g, {nonFiniteFunction(g)});
  TempDir dir;
  writeAll(lib, dir.path());
  const fs::path listing = dir / "includes.txt";
  const std::string command = "gcc -H -fsyntax-only -O2 -I" + dir.path().string() + " " +
                              (dir / lib.sources.at(0).path).string() + " 2> " + listing.string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command << "\n" << readFile(listing);
  const std::string included = readFile(listing);
  EXPECT_NE(included.find("robodiff/codegen/sincos_kernel.h"), std::string::npos) << "-H lists the headers read:\n" << included;
  EXPECT_EQ(included.find("/math.h"), std::string::npos) << included;
  EXPECT_EQ(included.find("/string.h"), std::string::npos) << included;
}

TEST(CPrologue, LibraryCallsAndNonFiniteConstantsUnderEveryCompiler) {
  Graph g;
  const FunctionDefinition f = nonFiniteFunction(g);
  const GeneratedLibrary lib = generateLibrary(g, {f});
  for (const std::string compiler : {"gcc", "clang", "tcc"}) {
    if (!haveProgram(compiler)) continue;
    SCOPED_TRACE(compiler);
    TempDir dir;
    CompilerOptions options;
    options.compiler = compiler;
    options.optimization = OptimizationLevel::O1;
    const CompileReport report = compileLibrary(lib, dir / "lib.so", options);
    const LoadedLibrary loaded = LoadedLibrary::open(report.library);
    const CompiledFunction compiled = loaded.function("f");
    std::vector<double> work(compiled.workSize() + 1), y(6, 0.0);
    const double x = 0.5;
    const double* in[] = {&x};
    double* out[] = {y.data()};
    compiled.evaluate(in, out, work.data());
    EXPECT_NEAR(y[0], std::sin(x), 1e-15);
    EXPECT_DOUBLE_EQ(y[1], std::sqrt(x + 3.0));
    EXPECT_TRUE(std::isinf(y[2]) && y[2] > 0) << y[2];
    EXPECT_TRUE(std::isinf(y[3]) && y[3] < 0) << y[3];
    EXPECT_TRUE(std::isnan(y[4])) << y[4];
    EXPECT_TRUE(std::isinf(y[5]) && y[5] > 0) << y[5];
  }
}

}  // namespace
}  // namespace robodiff::codegen
