// `robodiff eval`: a spec's outputs at one state, evaluated by the running server
// (LoadModel + GetFunction with wait + Evaluate), printed in the shapes of
// `robodiff compute --spec ... --derivatives` so that the two can be compared.
#include <iostream>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands/commands.hpp"
#include "options/function_options.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "service/service_connection.hpp"
#include "service/service_helpers.hpp"
#include "output/spec_output.hpp"
#include "output/state_json.hpp"
#include "output/user_spec_output.hpp"

namespace robodiff::cli {
namespace {

struct EvalArgs {
  ServiceArgs service;
  RobotArgs robot;
  std::string spec;
  StateArgs state;
  std::string format = "json";
};

OutputKind kindOf(rpc::OutputKind kind) {
  switch (kind) {
    case rpc::OutputKind::Value: return OutputKind::Value;
    case rpc::OutputKind::Jacobian: return OutputKind::Jacobian;
    case rpc::OutputKind::Hessian: return OutputKind::Hessian;
  }
  return OutputKind::Value;
}

// The concatenated input blocks the server asks for, from the state (checked against
// the model, as compute checks them).
std::vector<double> inputsFor(const EvalArgs& args, const Model& model, const rpc::GetFunctionReply& function,
                              const std::string& label, nlohmann::json& drawn) {
  int weights = 0;
  for (const rpc::InputBlock& b : function.inputs)
    if (b.name == "weights") weights = static_cast<int>(b.size);
  const auto [state, source] = loadState(args.state, model, weights);
  if (args.state.seed) drawn = drawnStateJson(*args.state.seed, state);
  std::vector<double> inputs;
  for (const rpc::InputBlock& b : function.inputs) {
    const Eigen::VectorXd& v = b.name == "weights" ? requireWeights(state, weights, label, source)
                                                   : require(state, model, b.name, label, source);
    if (v.size() != static_cast<Eigen::Index>(b.size))
      throw std::runtime_error("the server's function takes " + std::to_string(b.size) + " numbers for input '" +
                               b.name + "', " + source + " has " + std::to_string(v.size()));
    inputs.insert(inputs.end(), v.data(), v.data() + v.size());
  }
  return inputs;
}

// The server function's input blocks: name and size.
std::vector<std::pair<std::string, int>> inputBlocks(const rpc::GetFunctionReply& function) {
  std::vector<std::pair<std::string, int>> blocks;
  for (const rpc::InputBlock& b : function.inputs) blocks.emplace_back(b.name, static_cast<int>(b.size));
  return blocks;
}

// A user function's input blocks, read by name from the state (or drawn at random).
std::vector<double> userInputsFor(const EvalArgs& args, const Model& model, const rpc::GetFunctionReply& function,
                                  const FunctionSpec& spec, nlohmann::json& drawn) {
  const std::vector<std::pair<std::string, int>> blocks = inputBlocks(function);
  const std::vector<NamedInput> named = userNamedInputs(spec, blocks);
  const auto [runtime, source] = loadUserInputs(args.state, model, spec, named);
  if (args.state.seed) drawn = drawnInputsJson(*args.state.seed, named, runtime);
  std::vector<double> inputs;
  for (std::size_t b = 0; b < runtime.size(); ++b) {
    if (runtime[b].size() != blocks.at(b).second)
      throw std::runtime_error("the server's function takes " + std::to_string(blocks[b].second) +
                               " numbers for input '" + blocks[b].first + "', " + source + " has " +
                               std::to_string(runtime[b].size()));
    inputs.insert(inputs.end(), runtime[b].data(), runtime[b].data() + runtime[b].size());
  }
  return inputs;
}

// What eval prints besides the outputs.
nlohmann::json serviceMeta(const ServiceConnection& c, const rpc::LoadModelReply& loaded,
                           const rpc::GetFunctionReply& function) {
  return {{"transport", c.transport}, {"server", c.address}, {"model_id", loaded.model_id},
          {"function_id", function.function_id}};
}

void eval(const EvalArgs& args) {
  const std::string urdf = readTextFile(args.robot.urdf, "--urdf");
  const std::string spec_text = readTextFile(args.spec, "--spec");
  const Model model = loadRobot(args.robot);  // the state is checked and the tables labelled here
  ServiceConnection c = connectService(args.service);
  const rpc::LoadModelReply loaded = loadModelOnServer(c, urdf, args.robot.floating_base);
  if (static_cast<int>(loaded.nq) != model.nq || static_cast<int>(loaded.nv) != model.nv)
    throw std::runtime_error("the server's model has nq = " + std::to_string(loaded.nq) + ", nv = " +
                             std::to_string(loaded.nv) + "; " + args.robot.urdf + " loads here with nq = " +
                             std::to_string(model.nq) + ", nv = " + std::to_string(model.nv));
  // The server judges the spec first: its status and message are what a client would get.
  const rpc::GetFunctionReply function = getFunctionOnServer(c, loaded.model_id, spec_text, true);
  const FunctionSpec spec = parseFunctionSpec(spec_text, args.spec);
  const std::string label = spec.functionName();

  nlohmann::json drawn;  // what --random-state drew, printed as compute prints it
  const std::vector<double> inputs = spec.isUser() ? userInputsFor(args, model, function, spec, drawn)
                                                   : inputsFor(args, model, function, label, drawn);
  std::vector<double> outputs(rpc::outputCount(function));
  check(c->evaluate(function.function_id, inputs, outputs, c.call()), "Evaluate");

  std::vector<Eigen::MatrixXd> out;
  std::vector<OutputBlockInfo> blocks;
  std::size_t offset = 0;
  for (std::size_t k = 0; k < function.outputs.size(); ++k) {
    const rpc::OutputBlock& b = function.outputs[k];
    out.push_back(blockMatrix(b, std::span<const double>(outputs).subspan(offset, b.nnz)));
    offset += b.nnz;
    OutputBlockInfo info{b.name, kindOf(b.kind), {}};
    if (k < spec.outputs.size()) info.wrt = spec.outputs[k].wrt;
    blocks.push_back(std::move(info));
  }

  if (args.format == "table") {
    std::cout << label << " of " << (model.name.empty() ? args.robot.urdf : model.name) << " (nq = " << model.nq
              << ", nv = " << model.nv << ", evaluated by the server over " << c.transport << ")\n";
    if (spec.isUser()) printUserTables(std::cout, model, spec, userNamedInputs(spec, inputBlocks(function)), out);
    else printSpecTables(std::cout, model, spec, blocks, out);
    return;
  }
  nlohmann::json j;
  if (spec.isUser()) {
    j = {{"function", label}, {"backend", "service"}, {"nq", model.nq}, {"nv", model.nv}};
    j.update(serviceMeta(c, loaded, function));
    j = userOutputsJson(std::move(j), spec, out);
  } else {
    j = specOutputsJson(label, "service", model, spec, blocks, out);
    j.update(serviceMeta(c, loaded, function));
  }
  if (!drawn.is_null()) j["random_state"] = std::move(drawn);
  std::cout << j.dump() << "\n";
}

}  // namespace

void addEvalCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "Evaluate a spec's function at one state on the running server (LoadModel, GetFunction, Evaluate)");
  addRobotOptions(*cmd, args->robot);
  cmd->get_option("--urdf")->check(CLI::Validator(CLI::ExistingFile).description(""));
  addSpecOption(*cmd, args->spec, true)->check(CLI::Validator(CLI::ExistingFile).description(""));
  addStateOptions(*cmd, args->state);
  cmd->add_option("--format", args->format, "json (default) or table")->check(CLI::IsMember({"json", "table"}));
  addServiceOptions(*cmd, args->service);
  cmd->footer(std::string("Output (json): the shapes of `robodiff compute --spec SPEC --backend generated "
                          "--derivatives`: {\"function\", \"backend\": \"service\", \"nq\", \"nv\", \"value\", "
                          "\"jacobian\" [m][n], \"hessian\" [n][n], ...: one key per output block of the spec, named "
                          "as in the library, sparse blocks expanded; a user spec: one key per output, its name, "
                          "and its inputs read by name from --state}, plus \"transport\", \"server\", \"model_id\" "
                          "and \"function_id\". The spec is sent as it is: its outputs are printed (compute adds the "
                          "value when a spec lacks it). Waits until the server can evaluate the function (its "
                          "interpreter serves it while the library compiles).\n") +
              kServiceExitHelp);
  cmd->callback([args] {
    if (args->state.path.empty() && !args->state.seed) throw UsageError("--state FILE or --random-state SEED is required");
    eval(*args);
  });
}

}  // namespace robodiff::cli
