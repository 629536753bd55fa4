// FairScheduler's quota: a request stops counting against its client when its reply is
// about to be sent (answered()), not when the thread that served it gets round to the end
// of the task: a client that waits for each reply before sending the next is never refused.
#include <gtest/gtest.h>

#include "robodiff/server/fair_scheduler.hpp"

namespace robodiff::server {
namespace {

constexpr std::uint64_t kClient = 7;

TEST(FairScheduler, AnAnsweredPostedRequestNoLongerCountsThoughItsTaskRuns) {
  FairScheduler<int> s({/*max_queued=*/1, /*max_running=*/1});
  ASSERT_TRUE(s.push(kClient, 1));
  auto first = s.next();
  ASSERT_TRUE(first);
  ASSERT_TRUE(s.startPosted(kClient, first->item));
  QuotaSlot slot;
  slot.admit();
  EXPECT_FALSE(s.push(kClient, 2)) << "one pending, the quota";
  s.answered(kClient, slot);  // its reply goes out; the task has not ended yet
  EXPECT_EQ(s.pending(kClient), 0u);
  ASSERT_TRUE(s.push(kClient, 3)) << "refused although the client had its reply";
  EXPECT_FALSE(s.finishPosted(kClient, slot));  // nothing deferred
  EXPECT_EQ(s.pending(kClient), 1u) << "the answered request was released twice";
}

TEST(FairScheduler, AnInlineRequestIsReleasedOnceWhetherAnsweredOrNot) {
  FairScheduler<int> s({2, 1});
  ASSERT_TRUE(s.push(kClient, 1));
  ASSERT_TRUE(s.push(kClient, 2));
  QuotaSlot first, second;
  first.admit();
  second.admit();
  s.next();
  s.answered(kClient, first);
  s.answered(kClient, first);  // a second reply (a batch's next chunk) gives nothing back
  s.served(kClient, first);
  EXPECT_EQ(s.pending(kClient), 1u);
  s.next();
  s.served(kClient, second);  // dropped without a reply (a closed session)
  EXPECT_EQ(s.pending(kClient), 0u);
}

// A refused request's slot was never admitted: its error reply gives nothing back.
TEST(FairScheduler, ARefusedRequestsReplyGivesNothingBack) {
  FairScheduler<int> s({1, 1});
  ASSERT_TRUE(s.push(kClient, 1));
  QuotaSlot refused;
  EXPECT_FALSE(s.push(kClient, 2));
  s.answered(kClient, refused);
  EXPECT_EQ(s.pending(kClient), 1u);
}

TEST(FairScheduler, ADeferredRequestIsHandedOverWhenTheRunningOneEnds) {
  FairScheduler<int> s({3, 1});
  ASSERT_TRUE(s.push(kClient, 1));
  ASSERT_TRUE(s.push(kClient, 2));
  auto a = s.next(), b = s.next();
  ASSERT_TRUE(s.startPosted(kClient, a->item));
  EXPECT_FALSE(s.startPosted(kClient, b->item)) << "one running at a time";
  QuotaSlot slot;
  slot.admit();
  s.answered(kClient, slot);
  const auto next = s.finishPosted(kClient, slot);
  ASSERT_TRUE(next);
  EXPECT_EQ(*next, 2);
  EXPECT_EQ(s.pending(kClient), 1u);
}

}  // namespace
}  // namespace robodiff::server
