// The test processes' DDS domains (support/dds_domain.hpp): a claimed domain is nobody
// else's while its process lives, whether the other claimant is this process or another.
#include <sys/wait.h>
#include <unistd.h>

#include <set>
#include <stdexcept>

#include <gtest/gtest.h>

#include "support/dds_domain.hpp"

namespace robodiff::testing {
namespace {

// Ranges no other test claims from (theirs are 1..200 and 201..229), one per test, since
// a claim lasts as long as the process that may run them all.
TEST(DdsDomains, EachClaimOfARangeGetsADifferentDomainUntilNoneIsLeft) {
  std::set<std::uint32_t> claimed;
  for (int k = 0; k < 3; ++k) claimed.insert(claimDdsDomain(901, 903));
  EXPECT_EQ(claimed, (std::set<std::uint32_t>{901, 902, 903}));
  EXPECT_THROW(claimDdsDomain(901, 903), std::runtime_error);
}

TEST(DdsDomains, AnotherProcessDoesNotGetADomainThisOneHolds) {
  constexpr std::uint32_t kFirst = 904, kLast = 906;
  const std::uint32_t a = claimDdsDomain(kFirst, kLast), b = claimDdsDomain(kFirst, kLast);
  int pipe_fds[2];
  ASSERT_EQ(pipe(pipe_fds), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // exec would drop the inherited locks (O_CLOEXEC); closing them here does the same.
    for (int fd = 3; fd < 1024; ++fd)
      if (fd != pipe_fds[1]) close(fd);
    std::uint32_t got = 0;
    try {
      got = claimDdsDomain(kFirst, kLast);
    } catch (const std::exception&) {
    }
    _exit(write(pipe_fds[1], &got, sizeof got) == sizeof got ? 0 : 1);
  }
  close(pipe_fds[1]);
  std::uint32_t got = 0;
  ASSERT_EQ(read(pipe_fds[0], &got, sizeof got), static_cast<ssize_t>(sizeof got));
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_NE(got, 0u) << "the child found no free domain";
  EXPECT_NE(got, a);
  EXPECT_NE(got, b);
  EXPECT_GE(got, kFirst);
  EXPECT_LE(got, kLast);
}

TEST(DdsDomains, TheProcessDomainIsTheSameOnEveryCall) {
  EXPECT_EQ(testDomain(), testDomain());
  EXPECT_EQ(testDomain(1), testDomain(1));
  EXPECT_NE(emptyTestDomain(), testDomain());
  EXPECT_GE(testDomain(1), 201u);
  EXPECT_LE(testDomain(1), 229u);
}

}  // namespace
}  // namespace robodiff::testing
