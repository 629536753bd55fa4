// `robodiff security init|add-client|add-server`: a DDS Security keystore for robodiffd
// and its clients (layout and use: deploy/security.md).
#include <iostream>
#include <memory>
#include <string>

#include "commands/commands.hpp"
#include "robodiff/client/dds_keystore.hpp"

namespace robodiff::cli {
namespace {

struct SecurityArgs {
  std::string dir;
  std::string name;
  std::string service = "robodiff";
  bool operator_role = false;
  bool protect_metadata = false;
  int days = 3650;
  std::vector<std::string> also_calls;
};

client::KeystoreOptions keystoreOptions(const SecurityArgs& args) {
  client::KeystoreOptions options;
  options.service_name = args.service;
  options.valid_days = args.days;
  options.protect_metadata = args.protect_metadata;
  options.also_calls = args.also_calls;
  return options;
}

void printIdentity(const SecurityArgs& args, std::string_view role) {
  std::cout << "created " << role << " identity " << args.name << " in " << args.dir << "/identities/" << args.name
            << "\n  use: ROBODIFF_DDS_SECURITY=" << args.dir << "/" << args.name
            << (role == "server" ? "  or in robodiffd.conf: dds.security = \"" + args.dir +
                                       "\" and dds.security_identity = \"" + args.name + "\""
                                 : std::string())
            << "\n";
}

void addCommonOptions(CLI::App* cmd, const std::shared_ptr<SecurityArgs>& args) {
  cmd->add_option("--service", args->service, "Service name: topics <service>_request and <service>_reply")
      ->capture_default_str();
  cmd->add_option("--days", args->days, "Validity of the certificates and permissions, in days")
      ->check(CLI::Range(1, 36500))
      ->capture_default_str();
}

}  // namespace

void addSecurityCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("security", "Make a DDS Security keystore (CA, governance, identities)");
  cmd->require_subcommand(1);

  auto init_args = std::make_shared<SecurityArgs>();
  init_args->name = "robodiffd";
  CLI::App* init = cmd->add_subcommand(
      "init", "Create a keystore: CA, signed governance (everything encrypted) and the server identity");
  init->add_option("dir", init_args->dir, "Keystore directory (created)")->required();
  init->add_option("--server-name", init_args->name, "Name of the server identity")->capture_default_str();
  init->add_flag("--protect-metadata", init_args->protect_metadata,
                 "Also encrypt the RTPS submessages around the data (heartbeats, acknowledgements): "
                 "no forged ones on the path, at about 2x the round-trip latency of open DDS");
  addCommonOptions(init, init_args);
  init->callback([init_args] {
    client::initKeystore(init_args->dir, init_args->name, keystoreOptions(*init_args));
    std::cout << "created keystore " << init_args->dir << " (CA key in " << init_args->dir
              << "/private: keep it offline once every identity is made)\n";
    printIdentity(*init_args, "server");
  });

  auto client_args = std::make_shared<SecurityArgs>();
  CLI::App* add_client = cmd->add_subcommand(
      "add-client", "Add a client identity: certificate, key, permissions to call the service");
  add_client->add_option("dir", client_args->dir, "Keystore directory")->required();
  add_client->add_option("name", client_args->name, "Identity name (letters, digits, - _ .)")->required();
  add_client->add_flag("--operator", client_args->operator_role,
                       "An operator (writes requests in partition robodiff.operator.<name>: may see and act "
                       "on every caller's jobs, functions and models)");
  addCommonOptions(add_client, client_args);
  add_client->callback([client_args] {
    const auto role = client_args->operator_role ? client::IdentityRole::Operator : client::IdentityRole::Client;
    client::addIdentity(client_args->dir, client_args->name, role, keystoreOptions(*client_args));
    printIdentity(*client_args, client_args->operator_role ? "operator" : "client");
  });

  auto server_args = std::make_shared<SecurityArgs>();
  CLI::App* add_server = cmd->add_subcommand("add-server", "Add another server identity (a second robodiffd)");
  add_server->add_option("dir", server_args->dir, "Keystore directory")->required();
  add_server->add_option("name", server_args->name, "Identity name (letters, digits, - _ .)")->required();
  add_server->add_option("--also-calls", server_args->also_calls,
                         "A service this server also calls as a client (a fleet's robot host: its build hosts' "
                         "service; repeatable). One identity for both: Cyclone DDS allows one per process");
  addCommonOptions(add_server, server_args);
  add_server->callback([server_args] {
    client::addIdentity(server_args->dir, server_args->name, client::IdentityRole::Server,
                        keystoreOptions(*server_args));
    printIdentity(*server_args, "server");
  });
}

}  // namespace robodiff::cli
