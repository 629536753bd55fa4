// `robodiff load`: LoadModel on the server; prints the model id, nq, nv and the joints.
#include <fstream>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands/commands.hpp"
#include "service/service_connection.hpp"
#include "service/service_helpers.hpp"

namespace robodiff::cli {
namespace {

struct LoadArgs {
  ServiceArgs service;
  std::string urdf;
  bool floating_base = false;
  bool json = false;
};

std::string joinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

void load(const LoadArgs& args) {
  const std::string urdf = readTextFile(args.urdf, "--urdf");
  ServiceConnection c = connectService(args.service);
  const rpc::LoadModelReply model = loadModelOnServer(c, urdf, args.floating_base);
  if (args.json) {
    const nlohmann::ordered_json j = {{"model_id", model.model_id},   {"nq", model.nq},
                                      {"nv", model.nv},               {"joints", model.joint_names},
                                      {"frames", model.frame_names}, {"transport", c.transport}};
    std::cout << j.dump() << "\n";
    return;
  }
  std::cout << "model   " << model.model_id << "\n"
            << "nq      " << model.nq << "\n"
            << "nv      " << model.nv << "\n"
            << "joints  " << model.joint_names.size() << ": " << joinNames(model.joint_names) << "\n"
            << "frames  " << model.frame_names.size() << " (--json lists them)\n";
}

}  // namespace

void addLoadCommand(CLI::App& app) {
  auto args = std::make_shared<LoadArgs>();
  CLI::App* cmd = app.add_subcommand("load", "Load a robot on the running server (LoadModel): its model id, nq, nv, joints");
  cmd->add_option("--urdf", args->urdf, "Robot description (URDF file)")
      ->required()
      ->check(CLI::Validator(CLI::ExistingFile).description(""))
      ->type_name("FILE");
  cmd->add_flag("--floating-base", args->floating_base, "Add a free-flyer root joint");
  cmd->add_flag("--json", args->json,
                "Print {\"model_id\", \"nq\", \"nv\", \"joints\": [...], \"frames\": [...], \"transport\"}");
  addServiceOptions(*cmd, args->service);
  cmd->footer(std::string("The model stays loaded on the server (its id is a content hash: loading the same robot "
                          "again gives the same id).\n") +
              kServiceExitHelp);
  cmd->callback([args] { load(*args); });
}

}  // namespace robodiff::cli
