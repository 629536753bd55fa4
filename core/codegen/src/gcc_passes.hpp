// gcc's optimisation passes that generated code does not need, turned off to shorten
// its compile (docs/code-generation.md, "gcc's passes that generated code does not
// need"). Internal to the compiler driver.
#pragma once

#include <string>
#include <vector>

namespace robodiff::codegen::detail {

// The -fno-<pass> flags for the compiler whose `--version` printed `version_text`: the
// measured set for GNU's gcc 11 or newer; none for any other compiler (clang rejects
// most of them, tcc ignores them) or a text it cannot read.
std::vector<std::string> gccPassToggles(const std::string& version_text);

}  // namespace robodiff::codegen::detail
