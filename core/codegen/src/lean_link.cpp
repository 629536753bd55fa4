#include "lean_link.hpp"

#include "compiler_family.hpp"

namespace robodiff::codegen::detail {

// Generated code calls libm and at most memcpy and memset, which resolve at load time
// from the process's C library: not reading libc.so.6 and the start files saves ~5 ms a
// link, and without start files a -ffast-math library brings no crtfastmath.o (which
// turns on flush-to-zero in the loading thread). Measurements: docs/code-generation.md.
LinkArguments linkArguments(const std::string& version_text) {
  if (isGnuGcc(version_text)) return {{"-nostdlib"}, {"-lm", "-lgcc"}, {"-pipe"}};
  if (isClang(version_text)) return {{"-nostartfiles"}, {"-lm"}, {}};
  return {{}, {"-lm"}, {}};
}

}  // namespace robodiff::codegen::detail
