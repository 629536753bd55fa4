// `robodiff keygen --out DIR [--name NAME]`: an Ed25519 key pair for signing cache
// artifacts (NAME.key, private, 0600; NAME.pub, public). Never overwrites a key.
#include <iostream>
#include <memory>
#include <string>

#include "commands/commands.hpp"
#include "robodiff/cache/artifact_signing.hpp"

namespace robodiff::cli {
namespace {

struct KeygenArgs {
  std::string out;
  std::string name = "robodiff";
};

void makeKeyPair(const KeygenArgs& args) {
  const cache::SigningKey key = cache::SigningKey::generate();
  key.writePair(args.out, args.name);
  const std::filesystem::path dir(args.out);
  std::cout << "wrote " << (dir / (args.name + ".key")).string() << " (private, mode 0600: keep it on the build host)\n"
            << "wrote " << (dir / (args.name + ".pub")).string() << " (public: give it to the hosts that trust it)\n"
            << "key id " << key.keyId() << "\n";
}

}  // namespace

void addKeygenCommand(CLI::App& app) {
  auto args = std::make_shared<KeygenArgs>();
  CLI::App* cmd = app.add_subcommand("keygen", "Make an Ed25519 key pair for signing cache artifacts");
  cmd->add_option("--out", args->out, "Directory for the key files (created 0700 when missing)")
      ->required()
      ->type_name("DIR");
  cmd->add_option("--name", args->name, "Base name of the files: NAME.key and NAME.pub (default robodiff)")
      ->type_name("NAME");
  cmd->footer(
      "The private key (NAME.key, PEM PKCS#8, mode 0600) signs `robodiff cache export` bundles; a key file "
      "readable by group or others is refused. The public key (NAME.pub) is what `robodiff cache import "
      "--trust` accepts. The key id printed is the first 16 hex digits of the SHA-256 of the raw public key.\n"
      "Exit status: 0, or 1 when a file exists already (keys are never overwritten) or cannot be written.");
  cmd->callback([args] { makeKeyPair(*args); });
}

}  // namespace robodiff::cli
