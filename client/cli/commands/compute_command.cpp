// `robodiff compute`: evaluate one dynamics function in double precision at one state:
// its value straight from core/dynamics (the original output), or a spec's outputs
// (value, Jacobians, Hessians) by one of the backends (function_backends.hpp), or every
// output of a user function, its inputs read by name (user_spec_output.hpp). The
// generated backend takes its library from the content-addressed cache, building it
// there when missing (cached_library.hpp), unless --no-cache, or loads one `robodiff
// bench --keep` kept (--kept, kept_library.hpp).
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <utility>

#include <nlohmann/json.hpp>

#include "commands/commands.hpp"
#include "options/cache_location.hpp"
#include "options/cached_library.hpp"
#include "options/function_backends.hpp"
#include "options/function_options.hpp"
#include "options/kept_library.hpp"
#include "output/output_table.hpp"
#include "robodiff/dynamics/all.hpp"
#include "robodiff/functions/model_function.hpp"
#include "output/spec_output.hpp"
#include "output/state_json.hpp"
#include "output/user_spec_output.hpp"
#include "service/service_helpers.hpp"

namespace robodiff::cli {
namespace {

nlohmann::json placementJson(const SE3<double>& m) {
  return {{"translation", toJson(Eigen::VectorXd(m.translation))}, {"rotation", toJson(Eigen::MatrixXd(m.rotation))}};
}

struct ComputeOptions {
  RobotArgs robot;
  std::string function, spec, frame, reference = "LOCAL_WORLD_ALIGNED", format = "json";
  std::string backend;  // empty: reference, or interpreted for a user spec
  bool derivatives = false;
  StateArgs state;
  std::string cache_dir, compiler;  // the generated backend's cache (empty: the default) and compiler
  bool no_cache = false;            // generated: compile into a temporary directory instead
  std::string kept;                 // generated: the library `robodiff bench --keep` kept in this directory
};

const std::vector<std::string> kFunctions = {"rnea", "aba",      "crba", "gravity",  "nle",
                                             "fk",   "jacobian", "com",  "regressor"};

std::pair<State, std::string> loadState(const ComputeOptions& o, const Model& model, int weight_count = 0) {
  return cli::loadState(o.state, model, weight_count);
}

// The frame --frame names, checked against the model.
std::optional<int> namedFrame(const ComputeOptions& o, const Model& model) {
  if (o.frame.empty()) return std::nullopt;
  std::optional<int> frame = model.findFrame(o.frame);
  if (!frame) throw std::invalid_argument("--frame: no frame named '" + o.frame + "' in " + o.robot.urdf);
  return frame;
}

// The value of --function straight from core/dynamics (no --spec, --derivatives or
// other backend): the original output of `compute`.
void runDirect(const ComputeOptions& o) {
  Model model = loadRobot(o.robot);
  auto [state, source] = loadState(o, model);
  const std::string& fn = o.function;
  // Check the inputs the function needs in q, v, a, tau order, so the first problem is named.
  static const std::map<std::string, std::vector<std::string>> inputs = {
      {"rnea", {"q", "v", "a"}}, {"aba", {"q", "v", "tau"}}, {"crba", {"q"}},  {"gravity", {"q"}},
      {"nle", {"q", "v"}},       {"fk", {"q"}},              {"jacobian", {"q"}}, {"com", {"q"}},
      {"regressor", {"q", "v", "a"}}};
  for (const std::string& key : inputs.at(fn)) require(state, model, key, fn, source);
  auto need = [&](const char* key) -> const Eigen::VectorXd& { return require(state, model, key, fn, source); };
  const ReferenceFrame reference = parseReferenceFrame(o.reference);
  const std::optional<int> frame = namedFrame(o, model);
  if (fn == "jacobian" && !frame) throw std::invalid_argument("--function jacobian needs --frame NAME");

  Data<double> data(model);
  nlohmann::json result;
  Table table;
  const std::vector<std::string> vlabels = velocityLabels(model);
  if (fn == "rnea" || fn == "aba" || fn == "gravity" || fn == "nle") {
    Eigen::VectorXd out;
    if (fn == "rnea") out = rnea(model, data, need("q"), need("v"), need("a"));
    if (fn == "aba") out = aba(model, data, need("q"), need("v"), need("tau"));
    if (fn == "gravity") out = computeGeneralizedGravity(model, data, need("q"));
    if (fn == "nle") out = nonLinearEffects(model, data, need("q"), need("v"));
    result = toJson(out);
    table = Table::vector(fn == "aba" ? "ddq" : "tau", vlabels, out);
  } else if (fn == "crba" || fn == "regressor") {
    Eigen::MatrixXd out = fn == "crba" ? Eigen::MatrixXd(crba(model, data, need("q")))
                                       : jointTorqueRegressor(model, data, need("q"), need("v"), need("a"));
    result = toJson(out);
    table = fn == "crba" ? Table::matrix("M(q)", vlabels, out, vlabels) : Table::matrix("Y(q, v, a)", vlabels, out);
  } else if (fn == "fk") {
    forwardKinematics(model, data, need("q"));
    updateFramePlacements(model, data);
    result = nlohmann::json::object();
    table = Table::placements();
    for (int f = 0; f < model.nframes(); ++f) {
      if (frame && f != *frame) continue;
      result[model.frames[f].name] = placementJson(data.oMf[f]);
      table.addPlacement(model.frames[f].name, data.oMf[f].translation, data.oMf[f].rotation);
    }
  } else if (fn == "jacobian") {
    Eigen::MatrixXd J = computeFrameJacobian(model, data, need("q"), *frame, reference);
    result = toJson(J);
    table = Table::matrix(std::string("J(") + o.frame + ", " + toString(reference) + ")",
                          {"vx", "vy", "vz", "wx", "wy", "wz"}, J, vlabels);
  } else if (fn == "com") {
    Eigen::Vector3d com = centerOfMass(model, data, need("q"));
    result = {{"com", toJson(Eigen::VectorXd(com))}, {"mass", data.mass}};
    table = Table::vector("centre of mass", {"x", "y", "z", "total mass"},
                          Eigen::Vector4d(com.x(), com.y(), com.z(), data.mass));
  }
  if (o.format == "table") {
    std::cout << fn << " of " << (model.name.empty() ? o.robot.urdf : model.name) << " (nq = " << model.nq
              << ", nv = " << model.nv << ", " << source << ")\n";
    table.print(std::cout);
  } else {
    nlohmann::json out = {{"function", fn}, {"nq", model.nq}, {"nv", model.nv}, {"value", result}};
    if (fn == "jacobian") out["frame"] = o.frame, out["reference"] = toString(reference);
    if (o.state.seed) out["random_state"] = drawnStateJson(*o.state.seed, state);
    std::cout << out.dump() << "\n";
  }
}

// --function as a spec: its value and, with --derivatives, the Jacobian w.r.t. all its
// inputs. compute's "jacobian" is the spec's "frame_jacobian".
FunctionSpec specForFunction(const ComputeOptions& o, const Model& model) {
  const std::string name = o.function == "jacobian" ? "frame_jacobian" : o.function;
  const FunctionInfo* info = nullptr;
  for (const FunctionInfo& f : modelFunctions())
    if (name == f.name) info = &f;
  if (!info) throw std::invalid_argument("--function " + o.function + " has no spec form");
  nlohmann::json spec = {{"function", name}, {"outputs", {{{"kind", "value"}}}}};
  if (o.derivatives) spec["outputs"].push_back({{"kind", "jacobian"}, {"wrt", info->inputs}});
  if (info->needs_frame) {
    if (!namedFrame(o, model))
      throw std::invalid_argument("--function " + o.function + " needs --frame NAME with --derivatives or --backend");
    spec["frame"] = o.frame;
  }
  if (info->function == ModelFunction::FrameJacobian) spec["reference"] = o.reference;
  return parseFunctionSpec(spec.dump(), "--function " + o.function);
}

// The spec of --spec or --function, with the outputs compute prints: only the value
// without --derivatives, every output (and the value first if missing) with it.
FunctionSpec computedSpec(const ComputeOptions& o, const Model& model, const std::optional<FunctionSpec>& loaded) {
  FunctionSpec spec = loaded ? *loaded : specForFunction(o, model);
  const auto is_value = [](const OutputSpec& out) { return out.kind == OutputKind::Value; };
  if (!o.derivatives)
    spec.outputs = {OutputSpec{}};
  else if (std::none_of(spec.outputs.begin(), spec.outputs.end(), is_value))
    spec.outputs.insert(spec.outputs.begin(), OutputSpec{});
  return spec;
}

// The runtime inputs of `spec` from the state, in the function's block order: the
// variable inputs, then the Hessian weights if a Hessian takes them at runtime.
std::vector<Eigen::VectorXd> runtimeInputs(const ComputeOptions& o, const Model& model, const FunctionSpec& spec,
                                           const std::string& label, State& state_used) {
  int weights = 0;
  for (const OutputSpec& out : spec.outputs)
    if (out.kind == OutputKind::Hessian && !out.fixed_weights) {
      const auto [rows, cols] = valueShape(model, spec.function);
      weights = rows * cols;
    }
  auto [state, source] = loadState(o, model, weights);
  state_used = state;
  std::vector<Eigen::VectorXd> runtime;
  for (const std::string& name : functionInfo(spec.function).inputs)
    if (!spec.input(name).fixed) runtime.push_back(require(state, model, name, label, source));
  if (weights > 0) runtime.push_back(requireWeights(state, weights, label, source));
  return runtime;
}

// The blocks of the built function, for printing.
std::vector<OutputBlockInfo> blockInfos(const SpecFunction& f) {
  std::vector<OutputBlockInfo> blocks;
  for (const BuiltOutput& b : f.built().outputs) blocks.push_back({b.name, b.kind, b.wrt});
  return blocks;
}

// --backend, or the default: interpreted for a user spec (exact derivatives, nothing
// compiled), else reference.
std::string backendName(const ComputeOptions& o, bool user) {
  if (!o.backend.empty()) return o.backend;
  return user ? "interpreted" : "reference";
}

// The function for `backend`: traced, and with --no-cache compiled into a temporary
// directory; a cached generated library is opened by evaluateBy.
SpecFunction functionFor(const ComputeOptions& o, const Model& model, FunctionSpec spec, Backend backend) {
  LibraryOptions options;
  options.compiler.compiler = o.compiler;
  const bool cached = backend == Backend::Generated && !o.no_cache;
  return SpecFunction(model, std::move(spec), cached ? std::vector<Backend>{} : std::vector<Backend>{backend}, options);
}

// What a generated evaluation says about the cache: "hit" (the library was in it), "built"
// (built into it now), "off" (--no-cache), "kept" (--kept); empty for the other backends.
struct Evaluation {
  std::vector<Eigen::MatrixXd> outputs;
  std::string cache;
};

// f's outputs by `backend`; the generated library from the cache unless --no-cache.
Evaluation evaluateBy(const ComputeOptions& o, const Model& model, const SpecFunction& f, Backend backend,
                      const std::vector<Eigen::VectorXd>& runtime) {
  if (!o.kept.empty() && backend != Backend::Generated)
    throw std::invalid_argument("--kept loads a compiled library: it needs --backend generated");
  if (backend != Backend::Generated) return {f.evaluate(backend, runtime), ""};
  if (o.no_cache) return {f.evaluate(backend, runtime), "off"};
  if (!o.kept.empty()) return {evaluateKeptLibrary(model, f, o.kept, runtime), "kept"};
  CachedLibraryRequest request;
  request.cache_dir = cacheDirFor(o.cache_dir);
  request.compiler = o.compiler;
  request.urdf_text = readTextFile(o.robot.urdf, "--urdf");
  request.urdf_source = o.robot.urdf;
  request.floating_base = o.robot.floating_base;
  const std::string robot = model.name.empty() ? o.robot.urdf : model.name;
  const CachedLibrary library = CachedLibrary::open(model, f, request, [&] {
    std::cerr << "building " << f.spec().functionName() << " for " << robot << " into the cache "
              << request.cache_dir.string() << " ...\n";
  });
  return {library.evaluate(f, runtime), library.hit() ? "hit" : "built"};
}

// The table header's backend: the backend's name, and for a generated one, the cache.
std::string backendLabel(Backend backend, const std::string& cache) {
  std::string label = std::string(toString(backend)) + " backend";
  if (cache == "hit") label += ", from the cache";
  if (cache == "built") label += ", built into the cache";
  if (cache == "off") label += ", not cached";
  if (cache == "kept") label += ", kept by robodiff bench";
  return label;
}

// A spec's outputs (--spec, --derivatives or --backend) by the chosen backend.
void runSpec(const ComputeOptions& o, const std::optional<FunctionSpec>& loaded) {
  const Model model = loadRobot(o.robot);
  const FunctionSpec spec = computedSpec(o, model, loaded);
  const std::string label = o.function.empty() ? toString(spec.function) : o.function;
  State state;
  const std::vector<Eigen::VectorXd> runtime = runtimeInputs(o, model, spec, label, state);
  const Backend backend = parseBackend(backendName(o, false));
  const SpecFunction f = functionFor(o, model, spec, backend);
  const auto [out, cache] = evaluateBy(o, model, f, backend, runtime);
  if (o.format == "table") {
    std::cout << label << " of " << (model.name.empty() ? o.robot.urdf : model.name) << " (nq = " << model.nq
              << ", nv = " << model.nv << ", " << backendLabel(backend, cache) << ")\n";
    printSpecTables(std::cout, model, spec, blockInfos(f), out);
    return;
  }
  nlohmann::json j = specOutputsJson(label, toString(backend), model, spec, blockInfos(f), out);
  if (!cache.empty()) j["cache"] = cache;
  if (o.state.seed) j["random_state"] = drawnStateJson(*o.state.seed, state);
  std::cout << j.dump() << "\n";
}

// What the reference backend is for a user function, said wherever its numbers are printed.
constexpr const char* kUserReferenceValues = "double evaluation of the expressions";
constexpr const char* kUserReferenceDerivatives = "central finite differences (approximate)";

// The variable inputs of a user spec's built function, as read by name.
std::vector<NamedInput> userInputs(const SpecFunction& f) {
  std::vector<std::pair<std::string, int>> blocks;
  for (const codegen::InputBlock& b : f.definition().inputs) blocks.emplace_back(b.name, static_cast<int>(b.size));
  return userNamedInputs(f.spec(), blocks);
}

// A user spec: every output by the backend, the inputs read by name.
void runUser(const ComputeOptions& o, const FunctionSpec& spec) {
  if (!o.frame.empty()) throw std::invalid_argument("--frame does not apply to a user spec: its expressions name frames");
  const Model model = loadRobot(o.robot);
  const Backend backend = parseBackend(backendName(o, true));
  const SpecFunction f = functionFor(o, model, spec, backend);
  const std::vector<NamedInput> inputs = userInputs(f);
  const auto [runtime, source] = loadUserInputs(o.state, model, spec, inputs);
  const auto [out, cache] = evaluateBy(o, model, f, backend, runtime);
  const bool reference = backend == Backend::Reference;
  if (o.format == "table") {
    std::cout << spec.functionName() << " of " << (model.name.empty() ? o.robot.urdf : model.name)
              << " (nq = " << model.nq << ", nv = " << model.nv << ", " << source << ", "
              << backendLabel(backend, cache) << ")\n";
    if (reference)
      std::cout << "values by " << kUserReferenceValues << ", derivatives by " << kUserReferenceDerivatives << "\n";
    printUserTables(std::cout, model, spec, inputs, out);
    return;
  }
  nlohmann::json meta = {{"function", spec.functionName()}, {"backend", toString(backend)},
                         {"nq", model.nq}, {"nv", model.nv}};
  if (reference) meta["method"] = {{"values", kUserReferenceValues}, {"derivatives", kUserReferenceDerivatives}};
  if (!cache.empty()) meta["cache"] = cache;
  if (o.state.seed) meta["random_state"] = drawnInputsJson(*o.state.seed, inputs, runtime);
  std::cout << userOutputsJson(std::move(meta), spec, out).dump() << "\n";
}

void run(const ComputeOptions& o) {
  if (o.function.empty() == o.spec.empty()) throw std::invalid_argument("give one of --function NAME and --spec FILE");
  std::optional<FunctionSpec> spec;
  if (!o.spec.empty()) spec = loadFunctionSpec(o.spec);
  if (spec && spec->isUser()) runUser(o, *spec);
  else if (!spec && !o.derivatives && backendName(o, false) == "reference") runDirect(o);
  else runSpec(o, spec);
}

}  // namespace

void addComputeCommand(CLI::App& app) {
  auto options = std::make_shared<ComputeOptions>();
  CLI::App* cmd = app.add_subcommand("compute", "Evaluate a dynamics function, and its derivatives, at one state");
  addRobotOptions(*cmd, options->robot);
  auto* function = cmd->add_option("--function", options->function,
                                   "rnea|aba|crba|gravity|nle|fk|jacobian|com|regressor (jacobian: the frame "
                                   "Jacobian, frame_jacobian in a spec)")
                       ->check(CLI::IsMember(kFunctions));
  addSpecOption(*cmd, options->spec, false)->excludes(function);
  cmd->add_option("--frame", options->frame,
                  "Frame name (--function jacobian; restricts --function fk to one frame, and is required for fk "
                  "with --derivatives or --backend)");
  cmd->add_option("--reference", options->reference, "Jacobian reference frame (default LOCAL_WORLD_ALIGNED)")
      ->check(CLI::IsMember({"LOCAL", "WORLD", "LOCAL_WORLD_ALIGNED"}));
  addStateOptions(*cmd, options->state);
  cmd->add_option("--backend", options->backend,
                  "reference (default, except for a user spec): the value from core/dynamics in double; "
                  "derivatives from the builder's expression graph evaluated node by node "
                  "(symbolic::Graph::evaluate: slow, but no code generation or interpreter involved); for a user "
                  "spec, the values from the double evaluation of its expressions and the derivatives by central "
                  "finite differences (approximate). generated: the function's compiled library from the cache "
                  "(--cache), built there first by a robodiff-worker when missing (the same library warmup and "
                  "robodiffd build), loaded and run; with --no-cache compiled into a temporary directory instead "
                  "(removed afterwards). interpreted (the default for a user spec): the "
                  "same graph run by the interpreter, nothing compiled")
      ->check(CLI::IsMember(backendNames()));
  cmd->add_flag("--derivatives", options->derivatives,
                "Also print derivatives: with --function, the Jacobian w.r.t. all the function's inputs "
                "(\"jacobian\", [m][n], columns in input order, q in the tangent space); with --spec, every output "
                "the spec asks for, Hessians (full symmetric [n][n]) included. Without it only the value is printed. A user "
                "spec's outputs are always all printed");
  cmd->add_option("--format", options->format, "json (default) or table")->check(CLI::IsMember({"json", "table"}));
  CLI::Option* cache = cmd->add_option("--cache", options->cache_dir,
                                       "Cache directory of --backend generated (default: $ROBODIFF_CACHE_DIR, else "
                                       "$XDG_CACHE_HOME/robodiff, else ~/.cache/robodiff); created 0700; refused when "
                                       "other users may write to it")
                           ->type_name("DIR");
  cmd->add_flag("--no-cache", options->no_cache,
                "--backend generated: compile into a temporary directory (removed afterwards) and leave the cache "
                "alone: neither read nor written")
      ->excludes(cache);
  cmd->add_option("--kept", options->kept,
                  "--backend generated: load the library `robodiff bench --keep DIR` kept in DIR/<row> (its "
                  "<row>.json, <row>.so and src/) instead of the cache's, when it is the one this spec and robot "
                  "build (same normalised spec, same generated C: nothing is compiled); refused, named, otherwise")
      ->type_name("DIR")
      ->excludes(cache)
      ->excludes("--no-cache");
  cmd->add_option("--compiler", options->compiler,
                  "C compiler of --backend generated, a path or a name in PATH (default: $CC, else cc)")
      ->type_name("CC");
  cmd->footer(
      "Output (json): {\"function\", \"nq\", \"nv\", \"value\"} for --function alone (reference backend, no "
      "--derivatives); otherwise {\"function\", \"backend\", \"nq\", \"nv\", \"value\" (a vector, or [rows][cols]), "
      "\"jacobian\", \"hessian\", ...}: one key per output block of the function, named as in the generated "
      "library (several Jacobians: jacobian_q, jacobian_v, ...).\n"
      "A user spec (\"inputs\" / \"define\" / \"outputs\") reads its variable inputs by name from --state "
      "({\"q\": [...], \"u\": [...], ...}) and prints {\"function\", \"backend\", \"nq\", \"nv\"} and one key per "
      "output, its name: a value with one column, a gradient and a vjp as arrays, anything else [rows][cols] "
      "(sparse blocks expanded, a sparse Hessian mirrored to the full matrix). With the reference backend, "
      "\"method\" says the derivatives are central finite differences.\n"
      "With --random-state SEED the JSON also has \"random_state\": the seed and the arrays drawn, by input name, "
      "so the same state can be given again with --state FILE.\n"
      "With --backend generated the JSON also has \"cache\": \"hit\" (the library was in the cache: nothing "
      "compiled), \"built\" (built into the cache now; a later identical call is a hit), \"off\" (--no-cache) or "
      "\"kept\" (--kept). "
      "A cached library whose SHA-256 no longer matches the index is moved to the cache's quarantine and rebuilt, "
      "never loaded.");
  cmd->callback([options] { run(*options); });
}

}  // namespace robodiff::cli
