// bench/anchors: a generated library built in a child process of its own, as the
// CppADCodeGen and CasADi sides build theirs. The child's wall time is the cold build
// (everything `build` does: taping or expression building, code generation, the
// compiler), the compiler's peak memory as measured_cc logs it (getrusage(RUSAGE_CHILDREN)
// in the child without it), and a build over the cap is killed with its compilers and
// reported. The outcome is recorded
// in dir/build.txt, which a second round (--reuse) reads instead of building again.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "anchors.hpp"

namespace anchors {

// Empties `dir`, then runs `build` there (current directory) in a child process, within
// `cap_seconds`. Fills r.build_s, r.compiler_mib and r.status ("ok" only when `library`
// exists afterwards; "over_cap" or "failed" with a note otherwise).
void buildInChild(const std::filesystem::path& dir, const std::filesystem::path& library, double cap_seconds,
                  const std::function<void()>& build, RowResult& r);

// The compiler both generated sides run: measured_cc when ANCHORS_MEASURED_CC names it
// (bench/anchors/run does; it runs ANCHORS_REAL_CC), else /usr/bin/gcc itself.
std::string compilerCommand();

// The build of an earlier round, from dir/build.txt; false when there is none to reuse.
bool reuseBuild(const std::filesystem::path& dir, const std::filesystem::path& library, RowResult& r);

}  // namespace anchors
