// Starting a program in a forked child: the child's setup runs before exec, and a
// program that cannot be executed is reported by name and reason, with no child left.
#include "robodiff/process/spawn.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <fstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "support/temp_dir.hpp"

namespace robodiff::process {
namespace {

using robodiff::testing::TempDir;

// The child's stdout into the pipe's write end.
void stdoutInto(const void* context, int /*report_fd*/) { ::dup2(*static_cast<const int*>(context), 1); }

std::string readAll(int fd) {
  std::string text;
  char buf[256];
  ssize_t n;
  while ((n = ::read(fd, buf, sizeof buf)) > 0) text.append(buf, static_cast<std::size_t>(n));
  return text;
}

// No child of this process is left: failed starts are reaped.
bool noChildLeft() { return ::waitpid(-1, nullptr, WNOHANG) < 0 && errno == ECHILD; }

TEST(Spawn, RunsTheProgramAfterTheChildsSetup) {
  int out[2];
  ASSERT_EQ(::pipe2(out, O_CLOEXEC), 0);
  char* const argv[] = {const_cast<char*>("sh"), const_cast<char*>("-c"), const_cast<char*>("echo started; exit 3"),
                        nullptr};
  const Spawned child = spawn("/bin/sh", argv, stdoutInto, &out[1]);
  ::close(out[1]);
  ASSERT_TRUE(child.ok()) << child.error;
  EXPECT_EQ(readAll(out[0]), "started\n");
  ::close(out[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child.pid, &status, 0), child.pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 3) << "the program's own exit status";
}

TEST(Spawn, AMissingProgramIsNamedWithTheReasonAndLeavesNoChild) {
  char* const argv[] = {const_cast<char*>("nothing-here"), nullptr};
  const Spawned child = spawn("/nonexistent/nothing-here", argv);
  EXPECT_FALSE(child.ok());
  EXPECT_EQ(child.pid, -1);
  EXPECT_EQ(child.error, "cannot execute '/nonexistent/nothing-here': No such file or directory");
  EXPECT_TRUE(noChildLeft());
}

TEST(Spawn, AFileWithoutExecutePermissionIsRefusedWithTheReason) {
  TempDir dir;
  const auto script = dir / "not-executable.sh";
  std::ofstream(script) << "#!/bin/sh\nexit 0\n";
  char* const argv[] = {const_cast<char*>("not-executable.sh"), nullptr};
  const Spawned child = spawn(script.c_str(), argv);
  EXPECT_FALSE(child.ok());
  EXPECT_EQ(child.error, "cannot execute '" + script.string() + "': Permission denied");
  EXPECT_TRUE(noChildLeft());
}

// Whether `pid` still runs (a zombie awaiting its reaper counts as ended).
bool running(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return false;
  const auto close = line.rfind(')');
  return close != std::string::npos && close + 2 < line.size() && line[close + 2] != 'Z';
}

TEST(Spawn, TheParentDeathSignalEndsTheChildWithItsParent) {
  int pid_pipe[2];
  ASSERT_EQ(::pipe(pid_pipe), 0);
  const pid_t middle = ::fork();
  ASSERT_GE(middle, 0);
  if (middle == 0) {  // spawns a long sleep with SIGKILL as its death signal, then ends
    char* const argv[] = {const_cast<char*>("sleep"), const_cast<char*>("30"), nullptr};
    const Spawned child = spawn("/bin/sleep", argv, nullptr, nullptr, SIGKILL);
    (void)!::write(pid_pipe[1], &child.pid, sizeof child.pid);
    ::_exit(child.ok() ? 0 : 1);
  }
  ::close(pid_pipe[1]);
  pid_t sleeper = -1;
  ASSERT_EQ(::read(pid_pipe[0], &sleeper, sizeof sleeper), static_cast<ssize_t>(sizeof sleeper));
  ::close(pid_pipe[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(middle, &status, 0), middle);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_GT(sleeper, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (running(sleeper) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_FALSE(running(sleeper)) << "the sleep outlived the process that spawned it";
  if (running(sleeper)) ::kill(sleeper, SIGKILL);
}

}  // namespace
}  // namespace robodiff::process
