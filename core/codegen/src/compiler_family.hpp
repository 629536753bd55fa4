// Which compiler a `--version` text names: what the driver may ask of it beyond the
// portable flags (gcc_passes.hpp, lean_link.hpp). Internal to the compiler driver.
#pragma once

#include <string>

namespace robodiff::codegen::detail {

// GNU's gcc, whatever its program name (cc, gcc-12, x86_64-linux-gnu-gcc): its text
// names the Free Software Foundation and not clang.
bool isGnuGcc(const std::string& version_text);

// LLVM's clang (Debian's "clang version 14.0.6", Apple's, ...).
bool isClang(const std::string& version_text);

// The major version on the text's first line ("cc (Debian 12.2.0-14) 12.2.0" -> 12);
// 0 when it has none.
int majorVersion(const std::string& version_text);

}  // namespace robodiff::codegen::detail
