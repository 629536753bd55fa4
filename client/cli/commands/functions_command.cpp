// `robodiff functions`: the server's functions (ListFunctions) as a table or JSON.
#include <iostream>

#include <nlohmann/json.hpp>

#include "commands/commands.hpp"
#include "output/output_table.hpp"
#include "service/service_connection.hpp"

namespace robodiff::cli {
namespace {

struct FunctionsArgs {
  ServiceArgs service;
  std::string model;
  bool json = false;
};

std::string shortId(const std::string& id) { return id.size() > 16 ? id.substr(0, 16) : id; }

void listFunctions(const FunctionsArgs& args) {
  ServiceConnection c = connectService(args.service);
  rpc::ListFunctionsRequest request;
  request.model_id = args.model;
  rpc::ListFunctionsReply reply;
  check(client::listAllFunctions(*c.connection, request, reply.functions, c.call()), "ListFunctions");
  if (args.json) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const rpc::FunctionSummary& f : reply.functions)
      list.push_back({{"function_id", f.function_id},
                      {"model_id", f.model_id},
                      {"function", f.function_name},
                      {"state", rpc::toString(f.state)},
                      {"compiled", f.compiled},
                      {"evaluations", f.evaluations},
                      {"message", f.message}});
    std::cout << nlohmann::ordered_json{{"transport", c.transport}, {"functions", list}}.dump() << "\n";
    return;
  }
  if (reply.functions.empty()) {
    std::cout << (args.model.empty() ? "no functions on the server\n" : "no functions of model " + args.model + "\n");
    return;
  }
  Table table = Table::rows({"id", "model", "function", "state", "evaluator", "knots", "message"},
                            {false, false, false, false, false, true, false});
  for (const rpc::FunctionSummary& f : reply.functions) {
    const std::string evaluator = f.state == rpc::FunctionState::Ready ? (f.compiled ? "compiled" : "interpreted") : "-";
    std::string message = f.message.substr(0, f.message.find('\n'));
    if (message.size() > 100) message = message.substr(0, 97) + "...";  // --json has it whole
    table.addRow({shortId(f.function_id), shortId(f.model_id), f.function_name, rpc::toString(f.state), evaluator,
                  std::to_string(f.evaluations), message});
  }
  table.print(std::cout);
}

}  // namespace

void addFunctionsCommand(CLI::App& app) {
  auto args = std::make_shared<FunctionsArgs>();
  CLI::App* cmd = app.add_subcommand("functions", "List the running server's functions (ListFunctions)");
  cmd->add_option("--model", args->model, "Only the functions of this model (its full id, as `robodiff load` prints)")
      ->type_name("ID");
  cmd->add_flag("--json", args->json,
                "Print {\"transport\", \"functions\": [{\"function_id\", \"model_id\", \"function\", \"state\", "
                "\"compiled\", \"evaluations\", \"message\"}]} with full ids");
  addServiceOptions(*cmd, args->service);
  cmd->footer(std::string("Table: id and model (their first 16 hex digits), function, state (READY, BUILDING, "
                          "FAILED), evaluator (compiled, or interpreted while the library builds or when its build "
                          "failed), knots evaluated, message (why a build failed; its first 100 characters, --json has it whole).\n") +
              kServiceExitHelp);
  cmd->callback([args] { listFunctions(*args); });
}

}  // namespace robodiff::cli
