// The shared fixtures (codegen_fixtures.hpp), and tests that they are what they claim.
#include "codegen_fixtures.hpp"

#include <cmath>
#include <cstdlib>

#include <stdlib.h>
#include <unistd.h>

#include <fstream>
#include <iostream>
#include <sstream>

#include <gtest/gtest.h>

#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "support/process.hpp"

namespace robodiff::codegen::testing {

namespace {

class RandomGraphBuilder {
 public:
  RandomGraphBuilder(Graph& g, std::uint32_t seed, std::uint32_t inputs) : g_(g), rng_(seed) {
    for (std::uint32_t i = 0; i < inputs; ++i) pool_.push_back(g.input(i));
  }

  // Pool values stay within about [-4, 4].
  NodeId pick() {
    if (uniform(0, 9) == 0) return constant();
    // Prefer recent nodes, so the graph gets deep.
    const std::size_t n = pool_.size();
    const std::size_t lo = n > 12 ? n - 12 : 0;
    return pool_[uniform(uniform(0, 2) == 0 ? 0 : static_cast<int>(lo), static_cast<int>(n - 1))];
  }
  NodeId constant() {
    static const double values[] = {0.5, -1.75, 1.0 / 3.0, 2.0, -0.1, 3.141592653589793, 1e-3, -2.5};
    return g_.constant(values[uniform(0, 7)]);
  }
  NodeId squash(NodeId x) { return g_.unary(Op::Tanh, x); }                                     // (-1, 1)
  NodeId positive(NodeId x) { return g_.binary(Op::Add, g_.constant(1.5), squash(x)); }        // (0.5, 2.5)
  NodeId half(NodeId x) { return g_.binary(Op::Mul, g_.constant(0.5), x); }

  NodeId make(Op op) {
    switch (op) {
      case Op::Neg: return g_.unary(Op::Neg, pick());
      case Op::Sin: case Op::Cos: case Op::Atan: case Op::Tanh: case Op::Abs: return g_.unary(op, pick());
      case Op::Tan: return g_.unary(Op::Tan, squash(pick()));
      case Op::Asin: case Op::Acos: return g_.unary(op, g_.binary(Op::Mul, g_.constant(0.9), squash(pick())));
      case Op::Exp: return g_.unary(Op::Exp, squash(pick()));
      case Op::Log: case Op::Sqrt: return g_.unary(op, positive(pick()));
      case Op::Add: case Op::Sub: return half(g_.binary(op, pick(), pick()));
      case Op::Mul: return g_.binary(Op::Mul, g_.binary(Op::Mul, pick(), pick()), g_.constant(0.25));
      case Op::Div: return g_.binary(Op::Div, pick(), g_.binary(Op::Add, g_.constant(2.5), squash(pick())));
      case Op::Atan2: return g_.binary(Op::Atan2, pick(), pick());
      case Op::Pow: return g_.binary(Op::Pow, positive(pick()), squash(pick()));
      case Op::Min: case Op::Max: return g_.binary(op, pick(), pick());
      case Op::SelectPositive: return g_.selectPositive(pick(), pick(), pick());
      default: return pick();
    }
  }

  void grow(int operations) {
    static const Op ops[] = {Op::Neg, Op::Sin, Op::Cos, Op::Tan, Op::Asin, Op::Acos, Op::Atan, Op::Exp,
                             Op::Log, Op::Sqrt, Op::Tanh, Op::Abs, Op::Add, Op::Sub, Op::Mul, Op::Div,
                             Op::Atan2, Op::Pow, Op::Min, Op::Max, Op::SelectPositive};
    constexpr int kOps = sizeof(ops) / sizeof(ops[0]);
    for (int i = 0; i < operations; ++i) {
      // Every op at least once, then at random; sometimes a sin/cos pair of one argument.
      const Op op = i < kOps ? ops[i] : ops[uniform(0, kOps - 1)];
      if (op == Op::Sin && uniform(0, 1) == 0) {
        NodeId x = pick();
        pool_.push_back(g_.unary(Op::Sin, x));
        pool_.push_back(g_.unary(Op::Cos, x));
        continue;
      }
      pool_.push_back(make(op));
    }
  }

  int uniform(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  const std::vector<NodeId>& pool() const { return pool_; }

 private:
  Graph& g_;
  std::mt19937 rng_;
  std::vector<NodeId> pool_;
};

}  // namespace

FunctionDefinition randomFunction(Graph& g, const std::string& name, std::uint32_t seed, int operations) {
  const std::uint32_t a = 3 + seed % 3, b = 2 + seed % 2;  // two input blocks
  RandomGraphBuilder builder(g, seed, a + b);
  builder.grow(operations);
  const auto& pool = builder.pool();
  FunctionDefinition f;
  f.name = name;
  f.inputs = {{"x", a}, {"y", b}};
  // Dense 4 x 4: twelve sums that together read every pool node (so every op is
  // reached), a constant, an input, a negated input and a negated sum.
  std::vector<NodeId> dense(16, g.zero());
  for (std::size_t j = 0; j < pool.size(); ++j)
    dense[j % 12] = g.binary(j % 24 < 12 ? Op::Add : Op::Sub, dense[j % 12], pool[j]);
  dense[12] = g.constant(2.5);
  dense[13] = g.input(1);
  dense[14] = g.unary(Op::Neg, g.input(a));
  dense[15] = g.unary(Op::Neg, dense[0]);
  f.outputs.push_back(OutputBlock::dense("dense", 4, 4, dense));
  // Sparse 4 x 5: rows with 2, 0, 3, 1 nonzeros, products of pool nodes and a constant.
  std::vector<std::uint32_t> row_ptr{0, 2, 2, 5, 6}, col_idx{0, 3, 1, 2, 4, 2};
  std::vector<NodeId> values;
  const std::size_t half = pool.size() / 2;
  for (std::size_t i = 0; i < 6; ++i)
    values.push_back(g.binary(Op::Mul, pool[half + i * 5 % half], pool[i * 7 % half]));
  values[3] = g.constant(-0.1);
  f.outputs.push_back(OutputBlock::sparse("sparse", 4, 5, row_ptr, col_idx, values));
  return f;
}

FunctionDefinition chainFunction(Graph& g, const std::string& name, int joints) {
  // R = R * Rz(q) * Rx(c) (c a constant twist), p = p + R * offset.
  std::vector<NodeId> R{g.one(), g.zero(), g.zero(), g.zero(), g.one(), g.zero(), g.zero(), g.zero(), g.one()};
  std::vector<NodeId> p{g.zero(), g.zero(), g.zero()};
  auto mul = [&](NodeId a, NodeId b) { return g.binary(Op::Mul, a, b); };
  auto add = [&](NodeId a, NodeId b) { return g.binary(Op::Add, a, b); };
  auto sub = [&](NodeId a, NodeId b) { return g.binary(Op::Sub, a, b); };
  for (int j = 0; j < joints; ++j) {
    NodeId q = g.input(static_cast<std::uint32_t>(j));
    NodeId c = g.unary(Op::Cos, q), s = g.unary(Op::Sin, q);
    std::vector<NodeId> Rz{c, g.unary(Op::Neg, s), g.zero(), s, c, g.zero(), g.zero(), g.zero(), g.one()};
    const double twist = (j % 2 == 0) ? 1.5707963267948966 : 0.3;
    NodeId ct = g.constant(std::cos(twist)), st = g.constant(std::sin(twist));
    std::vector<NodeId> Rx{g.one(), g.zero(), g.zero(), g.zero(), ct, g.unary(Op::Neg, st), g.zero(), st, ct};
    auto matmul = [&](const std::vector<NodeId>& A, const std::vector<NodeId>& B) {
      std::vector<NodeId> C(9);
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) {
          NodeId sum = g.zero();
          for (int m = 0; m < 3; ++m) sum = add(sum, mul(A[r * 3 + m], B[m * 3 + k]));
          C[r * 3 + k] = sum;
        }
      return C;
    };
    R = matmul(matmul(R, Rz), Rx);
    const double offset[3] = {0.1 * (j + 1), -0.05, 0.3};
    for (int r = 0; r < 3; ++r) {
      NodeId d = g.zero();
      for (int m = 0; m < 3; ++m) d = add(d, mul(R[r * 3 + m], g.constant(offset[m])));
      p[r] = sub(p[r], g.unary(Op::Neg, d));  // p + d, written as p - (-d)
    }
  }
  FunctionDefinition f;
  f.name = name;
  f.inputs = {{"q", static_cast<std::uint32_t>(joints)}};
  f.outputs = {OutputBlock::dense("rotation", 3, 3, R), OutputBlock::dense("position", 3, 1, p)};
  return f;
}

FunctionDefinition triangularFunction(Graph& g, const std::string& name, int n) {
  std::vector<std::uint32_t> row_ptr{0}, col_idx;
  std::vector<NodeId> values, dense;
  for (int r = 0; r < n; ++r) {
    NodeId x = g.input(static_cast<std::uint32_t>(r));
    for (int c = 0; c <= r; ++c) {
      NodeId y = g.input(static_cast<std::uint32_t>(c));
      values.push_back(g.binary(Op::Sub, g.binary(Op::Mul, x, g.unary(Op::Cos, y)), g.constant(0.25 * c)));
      col_idx.push_back(static_cast<std::uint32_t>(c));
    }
    row_ptr.push_back(static_cast<std::uint32_t>(col_idx.size()));
    dense.push_back(g.binary(Op::Div, g.unary(Op::Sin, x), g.unary(Op::Neg, g.binary(Op::Add, g.constant(2.0), g.unary(Op::Abs, x)))));
  }
  FunctionDefinition f;
  f.name = name;
  f.inputs = {{"q", static_cast<std::uint32_t>(n)}};
  f.outputs = {OutputBlock::sparse("J", static_cast<std::uint32_t>(n), static_cast<std::uint32_t>(n), row_ptr, col_idx, values),
               OutputBlock::dense("g", static_cast<std::uint32_t>(n), 1, dense)};
  return f;
}

FunctionDefinition bandedFunction(Graph& g, const std::string& name, int n) {
  std::vector<NodeId> values;
  for (int c = 0; c < n; ++c)
    for (int r = 0; r < n; ++r) {
      const bool entry = std::abs(r - c) <= 1 || (r + 2 * c) % 7 == 0;
      const NodeId x = g.input(static_cast<std::uint32_t>(r)), y = g.input(static_cast<std::uint32_t>(c));
      values.push_back(entry ? g.binary(Op::Mul, g.unary(Op::Sin, x), y) : g.zero());
    }
  values[n * n - 1] = g.constant(-0.0);
  FunctionDefinition f;
  f.name = name;
  f.inputs = {{"q", static_cast<std::uint32_t>(n)}};
  f.outputs = {OutputBlock::dense("M", static_cast<std::uint32_t>(n), static_cast<std::uint32_t>(n), values)};
  return f;
}

std::vector<NodeId> limbValues(Graph& g, std::uint32_t first_input, bool skewed) {
  NodeId c = g.input(first_input), s = g.input(first_input + 1), e = g.constant(0.5);
  if (skewed) c = g.binary(Op::Mul, c, c);
  std::vector<NodeId> out;
  for (std::uint32_t i = 0; i < kLimbLinks; ++i) {
    const NodeId x = g.input(first_input + 2 + 2 * i), y = g.input(first_input + 3 + 2 * i);
    const NodeId c2 = g.binary(Op::Sub, g.binary(Op::Mul, c, x), g.binary(Op::Mul, s, y));
    const NodeId s2 = g.binary(Op::Add, g.binary(Op::Mul, s, x), g.binary(Op::Mul, c, y));
    e = g.binary(Op::Add, e, g.binary(Op::Div, c2, g.binary(Op::Add, g.one(), g.binary(Op::Mul, s2, s2))));
    c = c2;
    s = s2;
    out.push_back(e);
  }
  return out;
}

FunctionDefinition twoLimbsFunction(Graph& g, std::uint32_t cols) {
  constexpr std::uint32_t inputs = 2 + 2 * kLimbLinks;
  const std::vector<NodeId> left = limbValues(g, 0), right = limbValues(g, inputs);
  std::vector<NodeId> values;
  for (std::uint32_t i = 0; i < kLimbLinks; ++i) {
    values.push_back(left[i]);
    values.push_back(right[i]);
  }
  return FunctionDefinition{"limbs", {{"x", 2 * inputs}}, {OutputBlock::dense("e", 2 * kLimbLinks / cols, cols, values)}};
}

std::vector<bool> opsUsed(const Graph& g, const FunctionDefinition& f) {
  std::vector<char> needed(g.size(), 0);
  for (const auto& b : f.outputs)
    for (NodeId id : b.values) needed[id] = 1;
  std::vector<bool> used(static_cast<int>(Op::SelectPositive) + 1, false);
  for (std::size_t i = g.size(); i-- > 0;) {
    if (!needed[i]) continue;
    const auto& n = g.node(static_cast<NodeId>(i));
    used[static_cast<int>(n.op)] = true;
    for (int a = 0; a < symbolic::arity(n.op); ++a) needed[n.args[a]] = 1;
  }
  return used;
}

std::vector<std::vector<double>> randomInputs(const FunctionDefinition& f, std::uint64_t knots, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::vector<double>> in;
  for (const auto& b : f.inputs) {
    in.emplace_back(knots * b.size);
    for (double& x : in.back()) x = u(rng);
  }
  return in;
}

std::vector<std::vector<double>> outputBuffers(const FunctionDefinition& f, std::uint64_t knots) {
  std::vector<std::vector<double>> out;
  for (const auto& b : f.outputs) out.emplace_back(knots * b.size(), std::nan(""));
  return out;
}

std::vector<const double*> pointers(const std::vector<std::vector<double>>& blocks, const FunctionDefinition& f,
                                    std::uint64_t knot, bool inputs) {
  std::vector<const double*> p;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const std::uint64_t size = inputs ? f.inputs[b].size : f.outputs[b].size();
    p.push_back(blocks[b].data() + knot * size);
  }
  return p;
}

std::vector<double*> pointers(std::vector<std::vector<double>>& blocks, const FunctionDefinition& f,
                              std::uint64_t knot) {
  std::vector<double*> p;
  for (std::size_t b = 0; b < blocks.size(); ++b) p.push_back(blocks[b].data() + knot * f.outputs[b].size());
  return p;
}

std::vector<std::vector<double>> reference(const Graph& g, const FunctionDefinition& f,
                                           const std::vector<std::vector<double>>& inputs, std::uint64_t knot) {
  std::vector<double> flat;
  for (std::size_t b = 0; b < f.inputs.size(); ++b)
    for (std::uint32_t i = 0; i < f.inputs[b].size; ++i) flat.push_back(inputs[b][knot * f.inputs[b].size + i]);
  // Graph::evaluate may visit other functions' nodes of a shared graph: give every input.
  std::size_t graph_inputs = 0;
  for (const auto& n : g.nodes())
    if (n.op == Op::Input) graph_inputs = std::max<std::size_t>(graph_inputs, n.index + 1);
  flat.resize(std::max(flat.size(), graph_inputs), 0.0);
  std::vector<std::vector<double>> out;
  for (const auto& b : f.outputs) out.push_back(g.evaluate(b.values, flat));
  return out;
}

bool closeRelative(double a, double b, double tolerance) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (a == b) return true;
  return std::fabs(a - b) <= tolerance * std::max(std::fabs(a), std::fabs(b));
}

void expectCompiledAsTheGraph(const Graph& g, const FunctionDefinition& f, const GeneratedLibrary& lib,
                              double tolerance) {
  robodiff::testing::TempDir dir;
  const LoadedLibrary loaded = LoadedLibrary::open(compileLibrary(lib, dir / (f.name + ".so")).library);
  const CompiledFunction& compiled = loaded.function(f.name);
  std::vector<double> work(compiled.workSize() + 1);
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    const auto in = randomInputs(f, 1, seed);
    const auto expected = reference(g, f, in, 0);
    auto out = outputBuffers(f, 1);
    compiled.evaluate(pointers(in, f).data(), pointers(out, f).data(), work.data());
    for (std::size_t b = 0; b < out.size(); ++b)
      for (std::size_t k = 0; k < out[b].size(); ++k)
        EXPECT_NEAR(out[b][k], expected[b][k], tolerance) << "seed " << seed << ", block " << b << ", element " << k;
  }
}

bool haveProgram(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string candidate = dirs.substr(start, end - start) + "/" + program;
    if (access(candidate.c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

std::size_t countOf(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

bool cpuHasFlag(const std::string& flag) {
  std::ifstream in("/proc/cpuinfo");
  std::stringstream text;
  text << in.rdbuf();
  return text.str().find(" " + flag) != std::string::npos;
}

std::string disassembly(const std::filesystem::path& library, const std::string& symbol) {
  const std::string all = robodiff::testing::runCommand("objdump -d --no-show-raw-insn " + library.string()).out;
  const auto begin = all.find("<" + symbol + ">:\n");
  if (begin == std::string::npos) return {};
  return all.substr(begin, all.find("\n\n", begin) - begin);
}

std::vector<std::string> neededLibraries(const std::filesystem::path& library) {
  std::istringstream lines(robodiff::testing::runCommand("readelf -d '" + library.string() + "'").out);
  std::vector<std::string> needed;
  const std::string tag = "Shared library: [";
  for (std::string line; std::getline(lines, line);) {
    const auto at = line.find(tag);
    if (line.find("(NEEDED)") == std::string::npos || at == std::string::npos) continue;
    const auto first = at + tag.size();
    needed.push_back(line.substr(first, line.find(']', first) - first));
  }
  return needed;
}

GeneratedLibrary sinLibrary(Graph& g) {
  const NodeId x = g.input(0);
  FunctionDefinition f{"f", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {g.unary(Op::Sin, x)})}};
  return generateLibrary(g, {f});
}

double evaluateAt(const std::filesystem::path& library, double x) {
  const LoadedLibrary lib = LoadedLibrary::open(library);
  const CompiledFunction f = lib.function("f");
  double y = 0.0;
  const double* in[] = {&x};
  double* out[] = {&y};
  std::vector<double> work(f.workSize() + 1);
  f.evaluate(in, out, work.data());
  return y;
}

CompilerOptions withCompiler(const std::string& compiler) {
  CompilerOptions o;
  o.compiler = compiler;
  return o;
}

void forEachInstalledCompiler(const std::vector<std::string>& compilers, CompilerOptions options,
                              const std::function<void(const std::string&, const CompileReport&)>& check) {
  for (const std::string& compiler : compilers) {
    if (!haveProgram(compiler)) {
      std::cout << compiler << " is not installed: not checked\n";
      continue;
    }
    Graph g;
    robodiff::testing::TempDir dir;
    options.compiler = compiler;
    check(compiler, compileLibrary(sinLibrary(g), dir / "lib.so", options));
  }
}

TEST(CodegenFixtures, RandomFunctionsUseEveryOpAndStayFinite) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    Graph g;
    FunctionDefinition f = randomFunction(g, "f", seed, 120);
    ASSERT_NO_THROW(f.validate(g));
    auto used = opsUsed(g, f);
    for (int op = 0; op <= static_cast<int>(Op::SelectPositive); ++op)
      EXPECT_TRUE(used[op]) << "seed " << seed << " never uses " << symbolic::toString(static_cast<Op>(op));
    auto in = randomInputs(f, 1, seed);
    for (const auto& block : reference(g, f, in, 0))
      for (double v : block) EXPECT_TRUE(std::isfinite(v));
  }
}

}  // namespace robodiff::codegen::testing
