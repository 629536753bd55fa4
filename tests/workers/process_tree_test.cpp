// Killing a process tree: children, orphans (found through the session) and processes
// in process groups of their own all go; the caller's own group is never signalled.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>

#include <gtest/gtest.h>

// A private header of the workers library, tested directly: it is what keeps a killed
// worker from leaving compilers behind.
#include "../../workers/src/process_tree.hpp"
#include "worker_fixtures.hpp"

namespace robodiff::workers::detail {
namespace {

using namespace std::chrono_literals;
using testing::TempDir;

// Starts `sh -c script` as a child, leading a session of its own when `own_session`.
pid_t startShell(const std::string& script, bool own_session) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (own_session) ::setsid();
    ::execl("/bin/sh", "sh", "-c", script.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

// How a child ended, within a deadline: its wait status, or nullopt.
std::optional<int> reap(pid_t pid, std::chrono::milliseconds timeout = 5s) {
  std::optional<int> result;
  testing::waitFor(
      [&] {
        int status = 0;
        if (::waitpid(pid, &status, WNOHANG) == pid) result = status;
        return result.has_value();
      },
      timeout);
  return result;
}

TEST(ProcessTree, ReadsItsOwnStat) {
  const auto self = readProcessStat(::getpid());
  ASSERT_TRUE(self.has_value());
  EXPECT_EQ(self->pid, ::getpid());
  EXPECT_EQ(self->ppid, ::getppid());
  EXPECT_EQ(self->pgid, ::getpgrp());
  EXPECT_EQ(self->sid, ::getsid(0));
  EXPECT_EQ(self->state, 'R');
  EXPECT_FALSE(readProcessStat(0x3fffffff).has_value());
}

// A tree the way a killed worker leaves one, pids reported through a pipe: the root
// leads a session; it has a child in a process group of its own (as compilers are) and
// an orphan (its parent exited, so only the session still ties it to the tree).
struct Tree {
  pid_t root = -1, grouped = -1, orphan = -1;
};

Tree startTree() {
  int report[2];
  if (::pipe(report) != 0) throw std::runtime_error("pipe failed");
  Tree tree;
  tree.root = ::fork();
  if (tree.root == 0) {  // only async-signal-safe calls from here
    ::close(report[0]);
    ::setsid();
    const pid_t grouped = ::fork();
    if (grouped == 0) {
      ::setpgid(0, 0);
      for (;;) ::pause();
    }
    const pid_t middle = ::fork();
    if (middle == 0) {
      const pid_t orphan = ::fork();
      if (orphan == 0) {
        for (;;) ::pause();
      }
      const pid_t pids[2] = {grouped, orphan};
      (void)!::write(report[1], pids, sizeof pids);
      ::_exit(0);  // leaves its child an orphan
    }
    for (;;) ::pause();
  }
  ::close(report[1]);
  pid_t pids[2] = {-1, -1};
  const bool got = ::read(report[0], pids, sizeof pids) == static_cast<ssize_t>(sizeof pids);
  ::close(report[0]);
  if (!got) throw std::runtime_error("the tree did not report its pids");
  tree.grouped = pids[0];
  tree.orphan = pids[1];
  return tree;
}

TEST(ProcessTree, KillsChildrenInOtherGroupsAndOrphansOfTheSession) {
  const Tree tree = startTree();
  ASSERT_TRUE(testing::waitFor([&] {
    const auto orphan = readProcessStat(tree.orphan);
    const auto grouped = readProcessStat(tree.grouped);
    return orphan && orphan->ppid != tree.root && grouped && grouped->pgid == tree.grouped;
  })) << "the tree did not take its shape";
  EXPECT_EQ(readProcessStat(tree.orphan)->sid, tree.root);

  const std::vector<pid_t> killed = killProcessTree(tree.root);
  for (pid_t pid : {tree.grouped, tree.orphan}) {
    EXPECT_NE(std::find(killed.begin(), killed.end(), pid), killed.end()) << pid << " was not found in the tree";
    EXPECT_TRUE(testing::waitFor([&] { return testing::processIsDead(pid); }, 5s)) << pid << " survived";
  }
  const auto status = reap(tree.root);
  ASSERT_TRUE(status.has_value()) << "the root did not die";
  EXPECT_TRUE(WIFSIGNALED(*status) && WTERMSIG(*status) == SIGKILL);
  // The grouped child was the root's: reaped by init once the root died, or a zombie.
}

TEST(ProcessTree, NeverSignalsTheCallersGroup) {
  // The root shares this test's process group: killing "its group" would kill the test.
  const pid_t root = startShell("sleep 60", false);
  ASSERT_GT(root, 0);
  ASSERT_TRUE(testing::waitFor([&] {
    const auto s = readProcessStat(root);
    return s && s->pgid == ::getpgrp() && s->state == 'S';
  }));
  killProcessTree(root);
  const auto status = reap(root);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFSIGNALED(*status) && WTERMSIG(*status) == SIGKILL);
  // Still here.
}

TEST(ProcessTree, AnExitedRootsSessionIsSweptBeforeItIsReaped) {
  TempDir dir;
  const std::string d = dir.path().string();
  // The root leaves a child behind and exits; it stays a zombie until reaped here.
  const pid_t root = startShell("sleep 60 & echo $! > " + d + "/left.pid", true);
  ASSERT_TRUE(testing::waitFor([&] { return testing::pidFromFile(dir / "left.pid").has_value(); }));
  const pid_t left = *testing::pidFromFile(dir / "left.pid");
  ASSERT_TRUE(testing::waitFor([&] { return testing::processIsDead(root); }));
  EXPECT_FALSE(testing::processIsDead(left));

  killProcessTree(root);  // the zombie's pid still names its session
  EXPECT_TRUE(testing::waitFor([&] { return testing::processIsDead(left); }, 5s)) << "the leftover survived";
  const auto status = reap(root);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0);
}

}  // namespace
}  // namespace robodiff::workers::detail
