// docs/cli.md documents exactly the subcommands `robodiff --help` lists: one section
// headed `## robodiff <command>` for each, and none for a command that does not exist.
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "support/process.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

// The names under "Subcommands:" in CLI11's help text.
std::set<std::string> helpSubcommands(const std::string& help) {
  std::set<std::string> names;
  std::istringstream in(help);
  bool in_list = false;
  const std::regex entry(R"(^  ([a-z][a-z0-9-]*)\s)");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("Subcommands:", 0) == 0) {
      in_list = true;
      continue;
    }
    std::smatch m;
    if (in_list && std::regex_search(line, m, entry)) names.insert(m[1]);
  }
  return names;
}

std::set<std::string> documentedSubcommands(const std::string& page) {
  std::set<std::string> names;
  std::istringstream in(page);
  const std::regex heading(R"(^## robodiff ([a-z][a-z0-9-]*)\s*$)");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_match(line, m, heading)) names.insert(m[1]);
  }
  return names;
}

std::string listed(const std::set<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "(none)" : s;
}

TEST(Docs, CliPageListsEverySubcommand) {
  const ProcessResult help = runCommand(shellQuote(cliPath().string()) + " --help");
  ASSERT_EQ(help.exit_code, 0) << help.err;
  const std::set<std::string> commands = helpSubcommands(help.out);
  ASSERT_GE(commands.size(), 10u) << "could not read the subcommands from:\n" << help.out;
  const std::set<std::string> documented = documentedSubcommands(readFile(sourceDir() / "docs" / "cli.md"));

  std::set<std::string> missing, extra;
  for (const std::string& c : commands)
    if (!documented.count(c)) missing.insert(c);
  for (const std::string& d : documented)
    if (!commands.count(d)) extra.insert(d);
  EXPECT_TRUE(missing.empty()) << "docs/cli.md has no section `## robodiff <command>` for: " << listed(missing);
  EXPECT_TRUE(extra.empty()) << "docs/cli.md documents commands robodiff --help does not list: " << listed(extra);
}

TEST(Docs, HelpParserReadsCli11Lists) {
  const std::string help = "Usage: robodiff [OPTIONS] SUBCOMMAND\n\nOptions:\n  -h,--help   Print\n\n"
                           "Subcommands:\n  compute     Evaluate\n  make-robot  Write a robot\n";
  EXPECT_EQ(helpSubcommands(help), (std::set<std::string>{"compute", "make-robot"}));
}

}  // namespace
}  // namespace robodiff::testing
