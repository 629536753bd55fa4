// The compiler driver: generated sources in, a shared library out.
//
// It runs $CC (or `cc`) with flags from a fixed allowlist only (the optimisation level,
// optionally -march=native and -ffast-math; -fPIC -shared always; for gcc, the passes
// generated code does not need turned off, src/gcc_passes.hpp; for gcc and clang, a
// link without start files, src/lean_link.hpp), each compiler
// process under a wall-clock deadline and an address-space limit, keeps what the
// compiler printed (a failure reports it), compiles the parts of a split library in
// parallel, and writes the library atomically (a temporary name, then rename), so a
// reader never sees a half-written file.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "robodiff/codegen/c_emitter.hpp"

namespace robodiff::codegen {

enum class OptimizationLevel : std::uint8_t { O0, O1, O2, O3 };

struct CompilerOptions {
  // The compiler: one program, a path or a name looked up in PATH. Empty: $CC, or "cc"
  // when CC is unset.
  std::string compiler;
  OptimizationLevel optimization = OptimizationLevel::O2;
  bool native = false;     // -march=native: faster code (FMA, AVX), runs only on this kind of CPU
  // A named target instead (an x86-64 level, "x86-64-v3"): -march=<march> -mtune=generic,
  // code for every CPU of that level, not only this one. Overrides `native`.
  std::string march;
  bool fast_math = false;  // -ffast-math: changes results; only when asked for
  // Wall-clock limit of the whole build; compilers still running then are killed.
  std::chrono::milliseconds timeout = std::chrono::minutes(10);
  // Address-space limit (RLIMIT_AS) of each compiler process and its children; 0: none.
  std::uint64_t memory_limit_bytes = std::uint64_t{8} << 30;
  unsigned jobs = 2;  // translation units compiled at once
  // Where sources and objects are written: empty means a fresh directory under the
  // system's temporary directory, removed afterwards unless keep_build_dir.
  std::filesystem::path build_dir;
  bool keep_build_dir = false;
};

struct CompileReport {
  std::filesystem::path library;  // the written .so
  std::string compiler;           // the program that ran
  std::vector<std::string> flags;
  std::vector<std::string> commands;  // every command line run, in order
  double seconds = 0.0;               // wall clock of the whole build
  std::uint64_t peak_memory_bytes = 0;  // largest resident set of one compiler process tree
  std::string diagnostics;            // what the compilers printed (warnings), if anything
};

class CompileError : public std::runtime_error {
 public:
  enum class Kind : std::uint8_t {
    CompilerFailed,  // the compiler reported an error (compilerOutput() has it)
    Timeout,         // killed at the deadline
    MemoryLimit,     // ran out of memory under memory_limit_bytes
    CannotRun,       // no such compiler, or it could not be executed
    Io,              // writing sources or renaming the library failed
  };
  CompileError(Kind kind, const std::string& message, std::string compiler_output = {})
      : std::runtime_error(message), kind_(kind), compiler_output_(std::move(compiler_output)) {}
  Kind kind() const { return kind_; }
  const std::string& compilerOutput() const { return compiler_output_; }

 private:
  Kind kind_;
  std::string compiler_output_;
};

// Compiles `library` into the shared library `output` (its directory is created if
// needed). Throws CompileError; on failure `output` is left as it was.
CompileReport compileLibrary(const GeneratedLibrary& library, const std::filesystem::path& output,
                             const CompilerOptions& options = {});

// The program options.compiler (or $CC, or cc) names.
std::string compilerProgram(const CompilerOptions& options);

// The flags options lead to (the allowlist), as passed to every compiler command; a
// build with gcc adds its pass toggles (CompileReport::flags has them all).
std::vector<std::string> compilerFlags(const CompilerOptions& options);

// The compiler's first line of `--version` (or of `-v`, for tcc): its identity for
// cache keys. Asked once per compiler in a process. Throws CompileError when it cannot
// be run.
std::string compilerIdentity(const CompilerOptions& options);

// Whether the compiler driver assembles and links x86-64 AT&T assembly with AVX (gcc,
// clang; not tcc): CodegenOptions::assembly needs it. Throws CompileError when the
// compiler cannot be run.
bool compilerAssembles(const CompilerOptions& options);

}  // namespace robodiff::codegen
