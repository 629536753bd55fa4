// `robodiff make-robot`: writes a generated URDF (core/model robot_generator) to stdout
// or a file.
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>

#include "commands/commands.hpp"
#include "robodiff/model/robot_generator.hpp"

namespace robodiff::cli {
namespace {

struct MakeRobotArgs {
  std::string chain, tree, seed = "0", name, prismatic_fraction = "0", continuous_fraction = "0", out;
};

[[noreturn]] void badValue(const std::string& flag, const std::string& value, const std::string& why) {
  throw std::invalid_argument("make-robot: " + flag + " '" + value + "': " + why);
}

// The whole text must be the number: "12abc" or "" is an error, not 12 or 0.
template <class T> T parseNumber(const std::string& flag, const std::string& value, const char* expected) {
  T result{};
  const char* end = value.data() + value.size();
  auto [ptr, ec] = std::from_chars(value.data(), end, result);
  if (ec == std::errc::result_out_of_range) badValue(flag, value, std::string("out of range for ") + expected);
  if (ec != std::errc() || ptr != end) badValue(flag, value, std::string("expected ") + expected);
  return result;
}

void makeRobot(const MakeRobotArgs& args) {
  GeneratorOptions options;
  if (args.chain.empty() == args.tree.empty())
    throw std::invalid_argument("make-robot: give exactly one of --chain N and --tree SPEC");
  if (!args.chain.empty()) {
    options.kind = RobotKind::Chain;
    options.joints = parseNumber<int>("--chain", args.chain, "a whole number of joints");
    if (options.joints < 1 || options.joints > kMaxGeneratedJoints)
      badValue("--chain", args.chain, "a chain needs 1 to " + std::to_string(kMaxGeneratedJoints) + " joints");
  } else {
    options.kind = RobotKind::Tree;
    options.tree = args.tree;
    try {
      parseTreeSpec(args.tree);
    } catch (const std::invalid_argument& e) {
      badValue("--tree", args.tree, e.what());
    }
  }
  options.seed = parseNumber<std::uint64_t>("--seed", args.seed, "a whole number from 0 to 2^64-1");
  options.name = args.name;
  if (!args.name.empty() && !isValidRobotName(args.name))
    badValue("--name", args.name, "expected 1 to 200 letters, digits, '_', '.' or '-'");
  options.prismatic_fraction =
      parseNumber<double>("--prismatic-fraction", args.prismatic_fraction, "a number in [0, 1]");
  if (!(options.prismatic_fraction >= 0 && options.prismatic_fraction <= 1))
    badValue("--prismatic-fraction", args.prismatic_fraction, "expected a number in [0, 1]");
  options.continuous_fraction =
      parseNumber<double>("--continuous-fraction", args.continuous_fraction, "a number in [0, 1]");
  if (!(options.continuous_fraction >= 0 && options.continuous_fraction <= 1))
    badValue("--continuous-fraction", args.continuous_fraction, "expected a number in [0, 1]");
  if (options.prismatic_fraction + options.continuous_fraction > 1)
    throw std::invalid_argument("make-robot: --prismatic-fraction '" + args.prismatic_fraction +
                                "' and --continuous-fraction '" + args.continuous_fraction +
                                "' add up to more than 1");

  const std::string urdf = generateRobotUrdf(options);  // throws on the remaining problems
  if (args.out.empty()) {
    std::cout << urdf << std::flush;
    return;
  }
  std::ofstream file(args.out, std::ios::binary | std::ios::trunc);
  if (!file) badValue("--out", args.out, std::string("cannot open for writing: ") + std::strerror(errno));
  file << urdf;
  file.close();
  if (!file) badValue("--out", args.out, "write failed");
}

}  // namespace

void addMakeRobotCommand(CLI::App& app) {
  auto args = std::make_shared<MakeRobotArgs>();
  CLI::App* cmd = app.add_subcommand(
      "make-robot",
      "Write a random, physically valid robot as URDF: a serial chain or a tree of branches. "
      "The same options always give the same bytes.");
  cmd->add_option("--chain", args->chain, "A serial chain of N moving joints")->type_name("N");
  cmd->add_option("--tree", args->tree,
                  "Branches from the base: e.g. \"4x6\" (4 branches of 6 joints), \"2x6,2x7\", "
                  "\"leg:2x6,torso:2(arm:2x7,head:2)\" (labels name branches; a parenthesised "
                  "list hangs from the end of each branch of its group), or a preset: "
                  "\"quadruped\", \"humanoid\"")
      ->type_name("SPEC");
  cmd->add_option("--seed", args->seed, "Random seed (default 0)")->type_name("S");
  cmd->add_option("--name", args->name, "Robot name (default: chainN, treeN or the preset's name)");
  cmd->add_option("--prismatic-fraction", args->prismatic_fraction,
                  "Share of the moving joints that are prismatic (default 0)")
      ->type_name("F");
  cmd->add_option("--continuous-fraction", args->continuous_fraction,
                  "Share of the moving joints that are continuous (default 0)")
      ->type_name("F");
  cmd->add_option("--out", args->out, "Output file (default: stdout)")->type_name("FILE");
  cmd->callback([args] { makeRobot(*args); });
}

}  // namespace robodiff::cli
