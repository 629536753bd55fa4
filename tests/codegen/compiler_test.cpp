// The compiler driver: flags from the allowlist, failures that carry the compiler's
// message, the timeout, the memory limit, atomic output, $CC.
#include "robodiff/codegen/compiler.hpp"

#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>

#include "codegen_fixtures.hpp"
#include "robodiff/codegen/loaded_library.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
namespace fs = std::filesystem;

GeneratedLibrary smallLibrary() {
  Graph g;
  NodeId x = g.input(0);
  FunctionDefinition f{"f", {{"x", 1}}, {OutputBlock::dense("y", 1, 1, {g.unary(Op::Sin, x)})}};
  return generateLibrary(g, {f});
}

// An executable shell script standing in for a compiler.
fs::path script(const TempDir& dir, const std::string& name, const std::string& body) {
  const fs::path p = dir / name;
  std::ofstream(p) << "#!/bin/sh\n" << body << "\n";
  fs::permissions(p, fs::perms::owner_all);
  return p;
}

std::vector<std::string> filesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  return names;
}

CompilerOptions quick(const std::string& compiler = "gcc") {
  CompilerOptions o;
  o.compiler = compiler;
  o.optimization = OptimizationLevel::O1;
  return o;
}

TEST(CompilerFlags, ComeFromTheAllowlistOnly) {
  CompilerOptions o;
  EXPECT_EQ(compilerFlags(o), (std::vector<std::string>{"-O2", "-fPIC", "-fno-math-errno"}));
  o.optimization = OptimizationLevel::O3;
  o.native = true;
  o.fast_math = true;
  EXPECT_EQ(compilerFlags(o), (std::vector<std::string>{"-O3", "-march=native", "-ffast-math", "-fPIC", "-fno-math-errno"}));
}

TEST(Compiler, BuildsALibraryAndReportsTimeAndMemory) {
  TempDir dir;
  const CompileReport r = compileLibrary(smallLibrary(), dir / "lib.so", quick());
  EXPECT_EQ(r.library, dir / "lib.so");
  EXPECT_TRUE(fs::exists(r.library));
  EXPECT_GT(r.seconds, 0.0);
  EXPECT_GT(r.peak_memory_bytes, 1u << 20) << "the compiler's resident set (cc1 included)";
  ASSERT_EQ(r.commands.size(), 1u);
  EXPECT_NE(r.commands[0].find("-shared"), std::string::npos);
  EXPECT_NE(r.commands[0].find("-O1"), std::string::npos);
  // Only the library is left: no temporary name, no sources.
  EXPECT_EQ(filesIn(dir.path()), std::vector<std::string>{"lib.so"});
  std::cout << "compiled in " << r.seconds << " s, peak " << (r.peak_memory_bytes >> 20) << " MiB: " << r.commands[0]
            << "\n";
}

TEST(Compiler, ReplacesAnExistingLibraryAtomically) {
  TempDir dir;
  std::ofstream(dir / "lib.so") << "old";
  compileLibrary(smallLibrary(), dir / "lib.so", quick());
  EXPECT_GT(fs::file_size(dir / "lib.so"), 1000u);
  EXPECT_EQ(filesIn(dir.path()).size(), 1u);
}

TEST(Compiler, AFailureReportsTheCompilersMessage) {
  TempDir dir;
  const fs::path cc = script(dir, "failing-cc", "echo 'fake-cc: error: the sky is falling' >&2\nexit 1");
  std::ofstream(dir / "lib.so") << "previous";
  try {
    compileLibrary(smallLibrary(), dir / "lib.so", quick(cc.string()));
    FAIL() << "no error";
  } catch (const CompileError& e) {
    EXPECT_EQ(e.kind(), CompileError::Kind::CompilerFailed);
    EXPECT_NE(std::string(e.what()).find("the sky is falling"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("exit status 1"), std::string::npos) << e.what();
    EXPECT_NE(e.compilerOutput().find("the sky is falling"), std::string::npos);
  }
  // The previous library is untouched, and no temporary file is left.
  std::ifstream in(dir / "lib.so");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "previous");
  EXPECT_EQ(filesIn(dir.path()).size(), 2u);  // lib.so and the script
}

TEST(Compiler, ARealCompilerErrorIsReported) {
  TempDir dir;
  GeneratedLibrary broken;
  broken.sources.push_back({"broken.c", "int f(void) { return missing_variable; }\n"});
  try {
    compileLibrary(broken, dir / "lib.so", quick());
    FAIL() << "no error";
  } catch (const CompileError& e) {
    EXPECT_EQ(e.kind(), CompileError::Kind::CompilerFailed);
    EXPECT_NE(std::string(e.what()).find("missing_variable"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("broken.c"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "lib.so"));
}

TEST(Compiler, BinFalseIsAFailureWithNoOutput) {
  TempDir dir;
  try {
    compileLibrary(smallLibrary(), dir / "lib.so", quick("/bin/false"));
    FAIL() << "no error";
  } catch (const CompileError& e) {
    EXPECT_EQ(e.kind(), CompileError::Kind::CompilerFailed);
    EXPECT_NE(std::string(e.what()).find("printed nothing"), std::string::npos) << e.what();
  }
}

TEST(Compiler, TheTimeoutKillsTheCompiler) {
  TempDir dir;
  // The shell's child (sleep) is killed with it: the whole process group goes. It tells
  // its version like cc (asked before a build), then takes forever.
  const fs::path cc = script(dir, "slow-cc",
                             "case \"$1\" in --version) exec cc --version;; esac\n"
                             "echo compiling...\nsleep 30\necho done");
  CompilerOptions o = quick(cc.string());
  o.timeout = std::chrono::milliseconds(300);
  const auto start = std::chrono::steady_clock::now();
  try {
    compileLibrary(smallLibrary(), dir / "lib.so", o);
    FAIL() << "no error";
  } catch (const CompileError& e) {
    EXPECT_EQ(e.kind(), CompileError::Kind::Timeout);
    EXPECT_NE(std::string(e.what()).find("timed out"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0.3 s"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("compiling..."), std::string::npos) << e.what();
    std::cout << e.what() << "\n";
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  EXPECT_FALSE(fs::exists(dir / "lib.so"));
}

TEST(Compiler, TheMemoryLimitApplies) {
  TempDir dir;
  CompilerOptions o = quick();
  o.memory_limit_bytes = 20u << 20;  // far too little for cc1
  try {
    compileLibrary(smallLibrary(), dir / "lib.so", o);
    FAIL() << "no error";
  } catch (const CompileError& e) {
    EXPECT_EQ(e.kind(), CompileError::Kind::MemoryLimit) << e.what();
    EXPECT_NE(std::string(e.what()).find("20 MiB"), std::string::npos) << e.what();
    std::cout << e.what() << "\n";
  }
}

TEST(Compiler, AMissingCompilerCannotRun) {
  TempDir dir;
  for (const std::string cc : {"/nonexistent/cc", "no-such-compiler-robodiff"}) {
    try {
      compileLibrary(smallLibrary(), dir / "lib.so", quick(cc));
      FAIL() << "no error";
    } catch (const CompileError& e) {
      EXPECT_EQ(e.kind(), CompileError::Kind::CannotRun);
      EXPECT_NE(std::string(e.what()).find(cc), std::string::npos) << e.what();
    }
  }
  // A file that is there but not executable is named as such.
  const fs::path data = dir / "cc-without-x";
  std::ofstream(data) << "#!/bin/sh\n";
  try {
    compileLibrary(smallLibrary(), dir / "lib.so", quick(data.string()));
    FAIL() << "no error";
  } catch (const CompileError& e) {
    EXPECT_EQ(e.kind(), CompileError::Kind::CannotRun);
    EXPECT_NE(std::string(e.what()).find("'" + data.string() + "' is not an executable file"), std::string::npos)
        << e.what();
  }
  // Arguments in the compiler name would bypass the allowlist.
  EXPECT_THROW(compileLibrary(smallLibrary(), dir / "lib.so", quick("gcc -O3")), CompileError);
}

TEST(Compiler, UsesCCWhenNoCompilerIsGiven) {
  if (!haveProgram("tcc")) GTEST_SKIP() << "tcc is not installed";
  const char* old = std::getenv("CC");
  const std::string saved = old ? old : "";
  setenv("CC", "tcc", 1);
  TempDir dir;
  CompileReport r;
  try {
    r = compileLibrary(smallLibrary(), dir / "lib.so", CompilerOptions{});
  } catch (...) {
    old ? setenv("CC", saved.c_str(), 1) : unsetenv("CC");
    throw;
  }
  old ? setenv("CC", saved.c_str(), 1) : unsetenv("CC");
  EXPECT_EQ(fs::path(r.compiler).filename(), "tcc");
  EXPECT_NO_THROW(LoadedLibrary::open(r.library).function("f"));
  EXPECT_EQ(compilerProgram(CompilerOptions{}), old ? saved : std::string("cc"));
}

TEST(Compiler, IdentityNamesTheCompiler) {
  EXPECT_NE(compilerIdentity(quick("gcc")).find("gcc"), std::string::npos);
  if (haveProgram("tcc")) {
    EXPECT_NE(compilerIdentity(quick("tcc")).find("tcc"), std::string::npos);
  }
}

TEST(Compiler, CompilesPartsInParallelThenLinks) {
  Graph g;
  FunctionDefinition f = chainFunction(g, "fk", 4);
  CodegenOptions options;
  options.split_threshold = 30;
  const GeneratedLibrary lib = generateLibrary(g, {f}, options);
  ASSERT_GE(lib.sources.size(), 3u);
  TempDir dir;
  const CompileReport r = compileLibrary(lib, dir / "lib.so", quick());
  EXPECT_EQ(r.commands.size(), lib.sources.size() + 1);
  EXPECT_NE(r.commands.back().find("-shared"), std::string::npos);
  EXPECT_EQ(filesIn(dir.path()), std::vector<std::string>{"lib.so"});
}

TEST(Compiler, LeavesNoFileDescriptorsOrProcessesBehind) {
  auto openFds = [] { return std::distance(fs::directory_iterator("/proc/self/fd"), fs::directory_iterator()); };
  TempDir dir;
  const auto before = openFds();
  compileLibrary(smallLibrary(), dir / "a.so", quick());
  EXPECT_THROW(compileLibrary(smallLibrary(), dir / "b.so", quick("/bin/false")), CompileError);
  CompilerOptions slow = quick(script(dir, "slow-cc", "sleep 30 &\nsleep 30").string());
  slow.timeout = std::chrono::milliseconds(100);
  EXPECT_THROW(compileLibrary(smallLibrary(), dir / "c.so", slow), CompileError);
  EXPECT_EQ(openFds(), before);
  int status;
  EXPECT_EQ(waitpid(-1, &status, WNOHANG), -1) << "a child process was left behind";
  EXPECT_EQ(errno, ECHILD);
}

}  // namespace
}  // namespace robodiff::codegen
