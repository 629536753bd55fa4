#include "robodiff/codegen/compiler.hpp"

#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>

#include "compiler_family.hpp"
#include "gcc_passes.hpp"
#include "lean_link.hpp"
#include "robodiff/process/program_path.hpp"
#include "subprocess.hpp"

namespace robodiff::codegen {
namespace {

namespace fs = std::filesystem;
using detail::ProcessOutcome;
using Clock = std::chrono::steady_clock;

std::string mib(std::uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g s", s);
  return buf;
}

bool contains(const std::string& text, std::initializer_list<const char*> markers) {
  for (const char* m : markers)
    if (text.find(m) != std::string::npos) return true;
  return false;
}

// What compilers print when an allocation fails.
bool looksOutOfMemory(const std::string& output) {
  return contains(output, {"out of memory", "Out of memory", "memory exhausted", "Cannot allocate memory",
                           "cannot allocate", "bad_alloc"});
}

// What they print when, under an address-space limit, a mapping fails and they crash
// (gcc's cc1 segfaults, clang cannot even map its own libraries).
bool looksLikeMappingFailure(const std::string& output) {
  return contains(output, {"Segmentation fault", "failed to map segment", "terminated program", "Killed signal"});
}

// The error a failed process stands for.
CompileError failure(const ProcessOutcome& o, const std::string& command, const CompilerOptions& options) {
  using Kind = CompileError::Kind;
  const std::string output = o.output.empty() ? std::string("(the compiler printed nothing)") : o.output;
  switch (o.state) {
    case ProcessOutcome::State::CannotStart:
      return CompileError(Kind::CannotRun, "cannot run the compiler: " + o.start_error);
    case ProcessOutcome::State::TimedOut:
      return CompileError(Kind::Timeout,
                          "compilation timed out: the limit is " +
                              seconds(std::chrono::duration<double>(options.timeout).count()) +
                              " of wall-clock time and the compiler was killed: " + command +
                              (o.output.empty() ? std::string() : "\noutput so far:\n" + o.output),
                          o.output);
    case ProcessOutcome::State::Signaled:
      if (options.memory_limit_bytes > 0 && (o.signal == SIGSEGV || o.signal == SIGABRT || o.signal == SIGBUS ||
                                             o.signal == SIGKILL || looksOutOfMemory(o.output)))
        return CompileError(Kind::MemoryLimit,
                            "the compiler was killed by signal " + std::to_string(o.signal) + " (" +
                                strsignal(o.signal) + ") under the memory limit of " +
                                mib(options.memory_limit_bytes) + ", most likely out of memory: " + command +
                                "\n" + output,
                            o.output);
      return CompileError(Kind::CompilerFailed,
                          "the compiler was killed by signal " + std::to_string(o.signal) + " (" +
                              strsignal(o.signal) + "): " + command + "\n" + output,
                          o.output);
    default:
      break;
  }
  if (options.memory_limit_bytes > 0 && (looksOutOfMemory(o.output) || looksLikeMappingFailure(o.output)))
    return CompileError(Kind::MemoryLimit,
                        "the compiler ran out of memory (or crashed) under the memory limit of " +
                            mib(options.memory_limit_bytes) + " (exit status " + std::to_string(o.exit_code) +
                            "); raise CompilerOptions::memory_limit_bytes or split the function: " + command +
                            "\n" + output,
                        o.output);
  return CompileError(Kind::CompilerFailed,
                      "the compiler failed (exit status " + std::to_string(o.exit_code) + "): " + command + "\n" +
                          output,
                      o.output);
}

// A directory removed when the build is over (unless kept).
class BuildDirectory {
 public:
  explicit BuildDirectory(const CompilerOptions& options) {
    if (!options.build_dir.empty()) {
      path_ = options.build_dir;
      std::error_code ec;
      fs::create_directories(path_, ec);
      if (ec) throw CompileError(CompileError::Kind::Io, "cannot create " + path_.string() + ": " + ec.message());
      return;
    }
    std::string pattern = (fs::temp_directory_path() / "robodiff-build-XXXXXX").string();
    if (!mkdtemp(pattern.data()))
      throw CompileError(CompileError::Kind::Io, "cannot create a build directory " + pattern + ": " + strerror(errno));
    path_ = pattern;
    remove_ = !options.keep_build_dir;
  }
  ~BuildDirectory() {
    std::error_code ec;
    if (remove_) fs::remove_all(path_, ec);
  }
  BuildDirectory(const BuildDirectory&) = delete;
  BuildDirectory& operator=(const BuildDirectory&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool remove_ = false;
};

void writeFile(const fs::path& dir, const SourceFile& file) {
  const fs::path rel(file.path);
  if (rel.empty() || rel.is_absolute() || file.path.find("..") != std::string::npos)
    throw CompileError(CompileError::Kind::Io, "refusing to write source file '" + file.path + "' outside the build directory");
  const fs::path path = dir / rel;
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  std::ofstream out(path, std::ios::binary);
  out << file.text;
  out.close();
  if (!out) throw CompileError(CompileError::Kind::Io, "cannot write " + path.string());
}

std::string resolveCompiler(const CompilerOptions& options) {
  const std::string program = compilerProgram(options);
  if (program.empty()) throw CompileError(CompileError::Kind::CannotRun, "no compiler given");
  if (program.find_first_of(" \t") != std::string::npos)
    throw CompileError(CompileError::Kind::CannotRun,
                       "the compiler '" + program +
                           "' has arguments: give one program (flags come from CompilerOptions only)");
  const std::string path = process::findProgram(program);
  if (path.empty())
    throw CompileError(CompileError::Kind::CannotRun, "cannot run the compiler: " + process::whyNotFound(program));
  return path;
}

// The compiler's answer to --version (or to -v, tcc's) by `deadline`; empty when it
// gives none. Answers are kept per program path for the life of the process: asked
// once, they cost a build nothing more (a gcc answers in ~3 ms).
std::string versionText(const std::string& path, Clock::time_point deadline) {
  static std::mutex mutex;
  static std::map<std::string, std::string> known;
  {
    std::lock_guard lock(mutex);
    if (const auto it = known.find(path); it != known.end()) return it->second;
  }
  detail::ProcessLimits limits;
  limits.deadline = deadline;
  for (const char* flag : {"--version", "-v"}) {
    const auto outcome = detail::runProcesses({{path, flag}}, limits).at(0);
    if (outcome.ok() && !outcome.output.empty()) {
      std::lock_guard lock(mutex);
      return known.emplace(path, outcome.output).first->second;
    }
  }
  return {};
}

// The commands that build `library` in `dir` into `temp`: one compile-and-link for a
// single source; else one compile per source (run in parallel), then one link.
struct BuildCommands {
  std::vector<std::vector<std::string>> compile, link;
};

BuildCommands buildCommands(const GeneratedLibrary& library, const CompileReport& report,
                            const detail::LinkArguments& linking, const fs::path& dir, const fs::path& temp) {
  auto base = [&] {
    std::vector<std::string> argv{report.compiler};
    argv.insert(argv.end(), report.flags.begin(), report.flags.end());
    argv.push_back("-I" + dir.string());
    return argv;
  };
  auto linkInto = [&](std::vector<std::string>& argv, const std::vector<std::string>& inputs) {
    argv.insert(argv.end(), {"-shared", "-o", temp.string()});
    argv.insert(argv.end(), linking.before_inputs.begin(), linking.before_inputs.end());
    argv.insert(argv.end(), inputs.begin(), inputs.end());
    argv.insert(argv.end(), linking.libraries.begin(), linking.libraries.end());
  };
  BuildCommands commands;
  if (library.sources.size() == 1) {
    auto argv = base();
    argv.insert(argv.end(), linking.single_command.begin(), linking.single_command.end());
    linkInto(argv, {(dir / library.sources[0].path).string()});
    commands.compile.push_back(argv);
    return commands;
  }
  std::vector<std::string> objects;
  for (const auto& src : library.sources) {
    const fs::path source = dir / src.path;
    fs::path object = source;
    object.replace_extension(".o");
    auto argv = base();
    argv.insert(argv.end(), {"-c", "-o", object.string(), source.string()});
    commands.compile.push_back(argv);
    objects.push_back(object.string());
  }
  auto link_argv = base();
  linkInto(link_argv, objects);
  commands.link.push_back(link_argv);
  return commands;
}

// Runs `commands` (in parallel up to limits.jobs) into `report`: their command lines, the
// largest peak memory, their output. Throws the CompileError of the process that failed
// (not of those cancelled because of it) after removing `temp`.
void runCommands(const std::vector<std::vector<std::string>>& commands, const detail::ProcessLimits& limits,
                 const CompilerOptions& options, const fs::path& temp, CompileReport& report) {
  if (commands.empty()) return;
  const auto outcomes = detail::runProcesses(commands, limits);
  for (std::size_t i = 0; i < commands.size(); ++i) {
    report.commands.push_back(detail::commandLine(commands[i]));
    report.peak_memory_bytes = std::max(report.peak_memory_bytes, outcomes[i].peak_rss_bytes);
    report.diagnostics += outcomes[i].output;
  }
  std::error_code ec;
  for (std::size_t i = 0; i < commands.size(); ++i) {
    const auto& o = outcomes[i];
    if (!o.ok() && o.state != ProcessOutcome::State::Cancelled) {
      fs::remove(temp, ec);
      throw failure(o, detail::commandLine(commands[i]), options);
    }
  }
  for (const auto& o : outcomes) {
    if (!o.ok()) {
      fs::remove(temp, ec);
      throw failure(o, "(cancelled)", options);
    }
  }
}

// Where the library is linked before it is renamed into place: beside it, under a name
// unique to this process and call.
fs::path temporaryLibraryPath(const fs::path& output) {
  static std::atomic<unsigned> counter{0};
  const fs::path out_dir = output.parent_path().empty() ? fs::path(".") : output.parent_path();
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  return out_dir / ("." + output.filename().string() + ".tmp." + std::to_string(getpid()) + "." +
                    std::to_string(counter++));
}

}  // namespace

std::string compilerProgram(const CompilerOptions& options) {
  std::string program = options.compiler;
  if (program.empty()) {
    const char* cc = std::getenv("CC");
    program = cc && *cc ? cc : "cc";
  }
  const auto first = program.find_first_not_of(" \t");
  const auto last = program.find_last_not_of(" \t");
  return first == std::string::npos ? std::string() : program.substr(first, last - first + 1);
}

std::vector<std::string> compilerFlags(const CompilerOptions& options) {
  static const char* levels[] = {"-O0", "-O1", "-O2", "-O3"};
  std::vector<std::string> flags{levels[static_cast<int>(options.optimization)]};
  if (!options.march.empty()) {
    flags.push_back("-march=" + options.march);
    flags.push_back("-mtune=generic");
  } else if (options.native) {
    flags.push_back("-march=native");
  }
  if (options.fast_math) flags.push_back("-ffast-math");
  flags.push_back("-fPIC");
  // Library functions need not set errno (the generated code never reads it): lets the
  // compiler use the sqrt instruction. Values are unchanged.
  flags.push_back("-fno-math-errno");
  return flags;
}

namespace {

// The options' compiler's version text; CompileError when it tells none.
std::string toldVersion(const CompilerOptions& options) {
  const std::string path = resolveCompiler(options);
  const std::string text = versionText(path, Clock::now() + std::chrono::seconds(30));
  if (text.empty())
    throw CompileError(CompileError::Kind::CannotRun, "'" + path + "' does not tell its version (--version, -v)");
  return text;
}

}  // namespace

std::string compilerIdentity(const CompilerOptions& options) {
  const std::string text = toldVersion(options);
  return text.substr(0, text.find('\n'));
}

bool compilerAssembles(const CompilerOptions& options) {
  const std::string text = toldVersion(options);
  return detail::isGnuGcc(text) || detail::isClang(text);
}

CompileReport compileLibrary(const GeneratedLibrary& library, const fs::path& output, const CompilerOptions& options) {
  const auto started = Clock::now();
  if (library.sources.empty()) throw CompileError(CompileError::Kind::Io, "compileLibrary: no sources");
  CompileReport report;
  report.compiler = resolveCompiler(options);
  report.flags = compilerFlags(options);
  detail::ProcessLimits limits;
  if (options.timeout.count() > 0) limits.deadline = started + options.timeout;
  limits.address_space_bytes = options.memory_limit_bytes;
  limits.jobs = options.jobs;
  const std::string version_text = versionText(report.compiler, limits.deadline);
  for (std::string& f : detail::gccPassToggles(version_text)) report.flags.push_back(std::move(f));

  BuildDirectory build(options);
  for (const auto& f : library.headers) writeFile(build.path(), f);
  for (const auto& f : library.sources) writeFile(build.path(), f);

  const fs::path temp = temporaryLibraryPath(output);
  const BuildCommands commands =
      buildCommands(library, report, detail::linkArguments(version_text), build.path(), temp);
  runCommands(commands.compile, limits, options, temp, report);
  runCommands(commands.link, limits, options, temp, report);

  std::error_code ec;
  fs::rename(temp, output, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(temp, ec);
    throw CompileError(CompileError::Kind::Io, "cannot move the library to " + output.string() + ": " + why);
  }
  report.library = output;
  report.seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return report;
}

}  // namespace robodiff::codegen
