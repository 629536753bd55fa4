#include "lean_link.hpp"

#include "compiler_family.hpp"

namespace robodiff::codegen::detail {

// Generated code calls libm (sin ... fmax, sincos) and, at most, memcpy and memset.
// The C library is in every process that can load a library, so those two resolve at
// load time without it; reading libc.so.6's symbols and the start files took ~5 ms of
// each link (13 -> 8 ms). libgcc: whatever gcc may call for an operation it does not
// inline. -pipe lets the assembler run beside cc1 (2-3 ms of wall time); a split
// library's parallel compiles already fill the cores, so only a single command gets it.
// Without start files, a -ffast-math library does not bring crtfastmath.o either (gcc 12
// and clang 14 link it into shared libraries too): its constructor turns on
// flush-to-zero and denormals-are-zero in the thread that loads the library, for every
// other library that thread runs. clang keeps its C library and integrated assembler.
LinkArguments linkArguments(const std::string& version_text) {
  if (isGnuGcc(version_text)) return {{"-nostdlib"}, {"-lm", "-lgcc"}, {"-pipe"}};
  if (isClang(version_text)) return {{"-nostartfiles"}, {"-lm"}, {}};
  return {{}, {"-lm"}, {}};
}

}  // namespace robodiff::codegen::detail
