// Builds a generated library in a child process (child_build.hpp).
#include "child_build.hpp"

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

namespace anchors {

namespace fs = std::filesystem;

namespace {

std::string overCapNote(double cap) { return "build > " + std::to_string(static_cast<int>(cap)) + " s"; }

// The largest peak of the compilers measured_cc ran (its log: "<KiB> <output>" lines);
// 0 when it ran none.
long largestLoggedPeak(const fs::path& log) {
  std::ifstream in(log);
  long largest = 0, kib = 0;
  std::string output;
  while (in >> kib && std::getline(in, output)) largest = std::max(largest, kib);
  return largest;
}

// In the child: runs `build` in `dir`, records the compiler's peak memory; never returns.
// Through measured_cc (compilerCommand()), the compilers' own peak from its log; else
// getrusage's, which also counts this child's size at each fork (measured_cc.cpp).
[[noreturn]] void runChildBuild(const fs::path& dir, const std::function<void()>& build) {
  setpgid(0, 0);
  int code = 1;
  try {
    const fs::path log = fs::absolute(dir) / "compiler.log";
    setenv("ANCHORS_CC_LOG", log.c_str(), 1);
    fs::current_path(dir);
    build();
    rusage ru{};
    getrusage(RUSAGE_CHILDREN, &ru);
    const long logged = largestLoggedPeak(log);
    std::ofstream(dir / "compiler_kib") << (logged > 0 ? logged : ru.ru_maxrss) << "\n";
    code = 0;
  } catch (const std::exception& e) {
    std::ofstream(dir / "error") << e.what() << "\n";
  }
  _exit(code);
}

// Waits for the child `pid`, killing its process group past `cap` seconds from t0.
// Returns true when it was stopped at the cap.
bool waitWithinCap(pid_t pid, std::chrono::steady_clock::time_point t0, double cap, int& status) {
  for (;;) {
    if (waitpid(pid, &status, WNOHANG) == pid) return false;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > cap) {
      kill(-pid, SIGKILL);
      waitpid(pid, &status, 0);
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace

std::string compilerCommand() {
  const char* measured = std::getenv("ANCHORS_MEASURED_CC");
  return measured && *measured ? measured : "/usr/bin/gcc";
}

void buildInChild(const fs::path& dir, const fs::path& library, double cap_seconds,
                  const std::function<void()>& build, RowResult& r) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::fflush(nullptr);  // nothing buffered is written twice by the child
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) {
    r.status = "failed", r.note = "fork failed";
    return;
  }
  if (pid == 0) runChildBuild(dir, build);
  setpgid(pid, pid);
  int status = 0;
  const bool over = waitWithinCap(pid, t0, cap_seconds, status);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ofstream record(dir / "build.txt");
  if (over) {
    r.status = "over_cap", r.note = overCapNote(cap_seconds);
    record << "over_cap " << cap_seconds << "\n";
    return;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !fs::exists(library)) {
    std::string why = "build failed";
    if (std::ifstream err(dir / "error"); err) std::getline(err, why);
    r.status = "failed", r.note = why;
    record << "failed\n";
    return;
  }
  double kib = 0;
  std::ifstream(dir / "compiler_kib") >> kib;
  r.build_s = seconds, r.compiler_mib = kib / 1024.0;
  record << "ok " << seconds << " " << *r.compiler_mib << "\n";
}

bool reuseBuild(const fs::path& dir, const fs::path& library, RowResult& r) {
  std::ifstream record(dir / "build.txt");
  std::string status;
  if (!(record >> status)) return false;
  if (status == "over_cap") {
    double cap = 0;
    record >> cap;
    r.status = "over_cap", r.note = overCapNote(cap);
    return true;
  }
  if (status != "ok" || !fs::exists(library)) return false;
  double s = 0, mib = 0;
  record >> s >> mib;
  r.build_s = s, r.compiler_mib = mib;
  return true;
}

}  // namespace anchors
