// The interpreter on the RNEA and ABA Jacobians of a URDF: time per evaluation, the
// instruction count and (with --histogram) the most frequent opcodes and opcode pairs.
// With --save FILE / --check FILE: writes / compares the outputs bit for bit (to keep
// the interpreter's results identical across changes). Run by hand, never by ctest.
//   interpreter_bench URDF [--histogram] [--save F | --check F]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"

using namespace robodiff;

int main(int argc, char** argv) {
  if (argc < 2) return std::fprintf(stderr, "usage: interpreter_bench URDF [--histogram] [--save F | --check F]\n"), 2;
  bool histogram = false;
  std::string save, check;
  for (int k = 2; k < argc; ++k) {
    if (!std::strcmp(argv[k], "--histogram")) histogram = true;
    else if (!std::strcmp(argv[k], "--save") && k + 1 < argc) save = argv[++k];
    else if (!std::strcmp(argv[k], "--check") && k + 1 < argc) check = argv[++k];
  }
  const Model model = loadUrdfFile(argv[1]);
  const char* specs[][2] = {
      {"rnea_jacobian_dense", R"({"function": "rnea", "outputs": [{"kind": "value"},
        {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "dense"}]})"},
      {"aba_jacobian",
       R"({"function": "aba", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "tau"]}]})"}};
  std::vector<double> all_out;
  for (auto& s : specs) {
    const FunctionSpec spec = parseFunctionSpec(s[1]);
    const BuiltFunction built = buildFunction(model, spec);
    const codegen::Interpreter interp(*built.graph, built.definition);
    std::vector<std::vector<double>> in, out;
    for (const auto& x : randomRuntimeInputs(model, spec, 42)) in.emplace_back(x.data(), x.data() + x.size());
    for (const auto& b : built.definition.outputs) out.emplace_back(b.size());
    std::vector<const double*> ip;
    std::vector<double*> op;
    for (auto& v : in) ip.push_back(v.data());
    for (auto& v : out) op.push_back(v.data());
    std::vector<double> work(interp.workSize());
    auto once = [&] { interp.evaluate(ip.data(), op.data(), work.data()); };
    once();
    for (auto& v : out) all_out.insert(all_out.end(), v.begin(), v.end());
    double best = 1e9;
    for (int rep = 0; rep < 15; ++rep) {
      const int n = 2000;
      auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < n; ++k) once();
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / n;
      best = std::min(best, t);
    }
    std::printf("%-22s %7zu instructions (%zu after fusion)  %6zu groups  work %6zu  best %.3f us  (%.2f ns/instr)\n",
                s[0], interp.instructionCount(), interp.executedCount(), interp.groupCount(), interp.workSize(),
                best * 1e6, best * 1e9 / interp.executedCount());
    if (histogram) {
      const auto& code = interp.code();
      std::map<int, int> ops;
      std::map<std::pair<int, int>, int> pairs;
      for (std::size_t k = 0; k + 1 < code.size(); ++k) {
        ops[static_cast<int>(code[k].code)]++;
        pairs[{static_cast<int>(code[k].code), static_cast<int>(code[k + 1].code)}]++;
      }
      std::vector<std::pair<int, std::string>> lines;
      for (auto& [o, n] : ops) lines.push_back({n, "  op " + std::string(codegen::Interpreter::name(static_cast<codegen::Interpreter::Code>(o)))});
      for (auto& [p, n] : pairs)
        lines.push_back({n, "  pair " + std::string(codegen::Interpreter::name(static_cast<codegen::Interpreter::Code>(p.first))) +
                                " " + codegen::Interpreter::name(static_cast<codegen::Interpreter::Code>(p.second))});
      std::sort(lines.rbegin(), lines.rend());
      for (std::size_t k = 0; k < lines.size() && k < 30; ++k) std::printf("%6d %s\n", lines[k].first, lines[k].second.c_str());
    }
  }
  if (!save.empty()) std::ofstream(save, std::ios::binary).write(reinterpret_cast<const char*>(all_out.data()), all_out.size() * 8);
  if (!check.empty()) {
    std::vector<double> ref(all_out.size());
    std::ifstream(check, std::ios::binary).read(reinterpret_cast<char*>(ref.data()), ref.size() * 8);
    const bool same = std::memcmp(ref.data(), all_out.data(), ref.size() * 8) == 0;
    std::printf("outputs %s the saved ones\n", same ? "bit-identical to" : "DIFFER from");
    return same ? 0 : 1;
  }
  return 0;
}
