// `robodiff generate`: a spec and a robot to a compiled, self-describing function
// library on disk (generateFunctionLibrary), with a short summary of what was built.
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands/commands.hpp"
#include "output/human_units.hpp"
#include "options/function_backends.hpp"
#include "options/function_options.hpp"

namespace robodiff::cli {
namespace {

struct GenerateArgs {
  RobotArgs robot;
  std::string spec, out, name, compiler;
  std::optional<std::uint32_t> split_threshold;
  bool c_only = false;
};

std::string shape(const BuiltOutput& o) {
  std::string s = o.name + " " + std::to_string(o.rows) + " x " + std::to_string(o.cols);
  if (o.layout == Layout::Sparse) s += " (" + std::to_string(o.nnz) + " nonzeros)";
  return s;
}

void printSummary(const FunctionSpec& spec, const GeneratedFunctionLibrary& g, std::ostream& out) {
  const BuiltFunction& b = g.built;
  std::string outputs;
  for (const BuiltOutput& o : b.outputs) outputs += (outputs.empty() ? "" : ", ") + shape(o);
  std::string flags;
  for (const std::string& f : g.compile.flags) flags += " " + f;
  out << "function    " << b.definition.name << " (" << spec.functionName() << "): " << outputs << "\n"
      << "method      " << b.method << "\n"
      << "operations  " << g.info.operations << " in " << g.info.parts << (g.info.parts == 1 ? " part" : " parts")
      << "\n"
      << "seconds     trace " << formatFixed(b.timings.trace_seconds, 3) << ", differentiate "
      << formatFixed(b.timings.differentiate_seconds, 3) << ", emit " << formatFixed(g.emit_seconds, 3) << ", compile "
      << formatFixed(g.compile.seconds, 3) << "\n"
      << "compiler    " << g.compile.compiler << flags << ", peak memory "
      << formatFixed(static_cast<double>(g.compile.peak_memory_bytes) / (1024.0 * 1024.0), 1) << " MB\n"
      << "sizes       source " << g.source_bytes << " bytes, library " << g.library_bytes << " bytes\n"
      << "wrote       " << g.library.string() << "\n"
      << "            " << g.description.string() << "\n"
      << "            " << (g.library.parent_path() / "src").string() << "/\n";
}

void generate(const GenerateArgs& args) {
  const Model model = loadRobot(args.robot);
  const FunctionSpec spec = loadFunctionSpec(args.spec);
  LibraryOptions options;
  options.builder.name = args.name;
  options.compiler.compiler = args.compiler;
  if (args.split_threshold) options.codegen.split_threshold = *args.split_threshold;
  if (args.c_only) options.codegen.assembly = false;
  printSummary(spec, generateLibrary(model, spec, args.out, options), std::cout);
}

}  // namespace

void addGenerateCommand(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* cmd =
      app.add_subcommand("generate", "Generate, compile and describe a function library from a URDF and a spec");
  addRobotOptions(*cmd, args->robot);
  addSpecOption(*cmd, args->spec, true);
  cmd->add_option("--out", args->out,
                  "Output directory (created if needed): NAME.so (the library), NAME.json (its description: "
                  "inputs, outputs, shapes, how it was built) and src/ (the sources as compiled: C, or assembly)")
      ->required()
      ->type_name("DIR");
  cmd->add_option("--name", args->name,
                  "C name of the function and of the files (default: the spec's function, e.g. rnea, or a user "
                  "spec's \"name\")")
      ->type_name("NAME");
  cmd->add_option("--compiler", args->compiler, "C compiler to run, a path or a name in PATH (default: $CC, else cc)")
      ->type_name("CC");
  cmd->add_option("--split-threshold", args->split_threshold,
                  "Operations per translation unit before the function is cut into parts compiled in parallel "
                  "(default " +
                      std::to_string(LibraryOptions::defaultCodegenOptions().split_threshold) + "; 0: never split)")
      ->type_name("N");
  cmd->add_flag("--c-only", args->c_only,
                "Write C where the assembly back end would apply (single-knot builds for this CPU: "
                "docs/code-generation.md), to read or compare the C");
  cmd->callback([args] { generate(*args); });
}

}  // namespace robodiff::cli
