// robodiff._robodiff.check_spec: the three-way check of `robodiff check`
// (robodiff/functions/spec_check.hpp) on a robodiff.Function, for robodiff.check
// (robodiff/spec_check.py): its outputs at random states against the double reference
// and finite differences, and against the interpreter built here from the same spec.
#include <string>
#include <vector>

#include <nanobind/stl/string.h>

#include "bindings.hpp"
#include "function_call.hpp"
#include "reference_model.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/spec_check.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

// Spec problems as robodiff.Error, as Model.function reports them.
template <class Step>
auto specStep(Step&& step) -> decltype(step()) {
  try {
    return step();
  } catch (const SpecTooLarge& e) {
    throw client::ClientError({StatusCode::ResourceExhausted, e.what()});
  } catch (const symbolic::GraphTooLarge& e) {
    throw client::ClientError({StatusCode::ResourceExhausted, std::string("the function is too large to build: ") +
                                                                  e.what()});
  } catch (const SpecError& e) {
    throw client::ClientError({StatusCode::InvalidArgument, e.what()});
  }
}

// Refuses a Function whose blocks are not those of the function built here.
void requireSameLayout(const client::Function& f, const codegen::FunctionDefinition& def) {
  const rpc::GetFunctionReply& layout = f.layout();
  bool same = layout.inputs.size() == def.inputs.size() && layout.outputs.size() == def.outputs.size();
  for (std::size_t b = 0; same && b < def.inputs.size(); ++b)
    same = layout.inputs[b].name == def.inputs[b].name && layout.inputs[b].size == def.inputs[b].size;
  for (std::size_t k = 0; same && k < def.outputs.size(); ++k) {
    const rpc::OutputBlock& o = layout.outputs[k];
    const std::size_t values = o.layout == rpc::OutputLayout::SparseCsr ? o.nnz : std::size_t{o.rows} * o.cols;
    same = o.name == def.outputs[k].name && values == def.outputs[k].size();
  }
  if (!same)
    throw nb::value_error(("function " + f.id() + " is not the spec's function on this model: its input and output " +
                           "blocks differ from those built here")
                              .c_str());
}

// The Function's output blocks at the runtime inputs, each block's doubles in its wire
// layout (what the generated code writes), as specBlockMatrices reads them.
std::vector<Eigen::VectorXd> functionBlocks(const client::Function& f, const std::vector<Eigen::VectorXd>& runtime) {
  std::vector<double> in, out(f.outputCount());
  for (const Eigen::VectorXd& block : runtime) in.insert(in.end(), block.data(), block.data() + block.size());
  const Status status = f.evaluate(in, out);
  if (!status.ok()) throw client::ClientError(status);
  std::vector<Eigen::VectorXd> blocks;
  std::size_t offset = 0;
  for (const rpc::OutputBlock& o : f.layout().outputs) {
    const std::size_t values = o.layout == rpc::OutputLayout::SparseCsr ? o.nnz : std::size_t{o.rows} * o.cols;
    blocks.push_back(Eigen::Map<const Eigen::VectorXd>(out.data() + offset, static_cast<Eigen::Index>(values)));
    offset += values;
  }
  return blocks;
}

nb::dict comparisonDict(const SpecComparison& c) {
  nb::dict d;
  d["output"] = c.output;
  d["against"] = c.against;
  d["worst_abs_error"] = c.worst_abs;
  d["worst_rel_error"] = c.worst_rel;
  d["state"] = c.state;
  d["seed"] = c.seed;
  d["row"] = static_cast<long long>(c.row);
  d["col"] = static_cast<long long>(c.col);
  d["tolerance"] = c.tolerance;
  d["passed"] = c.pass();
  return d;
}

// function: the Function to check (with the interpreter beside it), or None to check
// the interpreter alone.
nb::dict checkSpec(const ReferenceModel& m, const std::string& spec_json, const PyFunction* function,
                   int samples, std::uint64_t seed) {
  if (samples < 1) throw nb::value_error(("samples: " + std::to_string(samples) + " given; 1 or more is needed").c_str());
  std::vector<SpecComparison> rows;
  std::string name;
  {
    nb::gil_scoped_release release;
    const FunctionSpec spec = specStep([&] { return parseFunctionSpec(spec_json, "spec"); });
    const BuiltFunction built = specStep([&] { return buildFunction(m.model(), spec); });
    name = built.definition.name;
    const codegen::Interpreter interpreter(*built.graph, built.definition);
    const BlockEvaluator interpreted = [&](const std::vector<Eigen::VectorXd>& runtime) {
      return specBlockMatrices(spec, built, evaluateBlocks(interpreter, built.definition, runtime));
    };
    const client::Function* tested = function ? &function->function() : nullptr;
    if (tested) requireSameLayout(*tested, built.definition);
    const BlockEvaluator compiled = [&](const std::vector<Eigen::VectorXd>& runtime) {
      return specBlockMatrices(spec, built, functionBlocks(*tested, runtime));
    };
    rows = checkSpecFunction(m.model(), spec, built, tested ? compiled : interpreted,
                             tested ? interpreted : BlockEvaluator(), {samples, seed});
  }
  nb::list comparisons;
  for (const SpecComparison& c : rows) comparisons.append(comparisonDict(c));
  nb::dict result;
  result["function"] = name;
  result["comparisons"] = comparisons;
  return result;
}

}  // namespace

void bindCheck(nb::module_& m) {
  m.def("check_spec", &checkSpec, nb::arg("model"), nb::arg("spec_json"), nb::arg("function").none(),
        nb::arg("samples"), nb::arg("seed"),
        "The three-way check of `robodiff check` (robodiff.check wraps it): function's outputs (None: the "
        "interpreter's) at `samples` random states from `seed`, against the double reference and finite "
        "differences, and against the interpreter. Returns {'function': name, 'comparisons': [dict per output "
        "and reference]}.");
}

}  // namespace robodiff::python
