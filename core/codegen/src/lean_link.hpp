// How the driver links a library: with gcc against libm alone, with clang without start
// files (docs/code-generation.md, "A lean link"). Internal to the compiler driver.
#pragma once

#include <string>
#include <vector>

namespace robodiff::codegen::detail {

struct LinkArguments {
  std::vector<std::string> before_inputs;  // after -shared, before the sources or objects
  std::vector<std::string> libraries;      // after them
  // Added to a library's only command when it is compiled and linked in one.
  std::vector<std::string> single_command;
};

// For the compiler whose `--version` printed `version_text`. GNU's gcc: no start files,
// no C library (-nostdlib), then libm and libgcc; one command through pipes. clang: no
// start files (-nostartfiles), libm. Any other compiler, or a text it cannot read: its
// default link, and libm.
LinkArguments linkArguments(const std::string& version_text);

}  // namespace robodiff::codegen::detail
