// RecentRing, the dashboard history's store: bounded (the oldest go), oldest first, a
// filter on read, a clear refusal of capacity 0, and correct under concurrent writers and
// readers (every writer's surviving values are its latest ones, in its order).
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "robodiff/server/recent_ring.hpp"

namespace robodiff::testing {
namespace {

using server::RecentRing;

TEST(RecentRing, KeepsTheLatestValuesOldestFirst) {
  RecentRing<int> ring(3);
  EXPECT_EQ(ring.capacity(), 3u);
  EXPECT_TRUE(ring.snapshot().empty());
  ring.push(1);
  ring.push(2);
  EXPECT_EQ(ring.snapshot(), (std::vector<int>{1, 2}));
  for (int v = 3; v <= 7; ++v) ring.push(v);
  EXPECT_EQ(ring.snapshot(), (std::vector<int>{5, 6, 7}));
  EXPECT_EQ(ring.size(), 3u);
  EXPECT_EQ(ring.pushed(), 7u);
  EXPECT_EQ(ring.snapshotIf([](int v) { return v > 5; }), (std::vector<int>{6, 7}));
}

TEST(RecentRing, CapacityOneHoldsTheLastValue) {
  RecentRing<int> ring(1);
  for (int v = 0; v < 5; ++v) ring.push(v);
  EXPECT_EQ(ring.snapshot(), (std::vector<int>{4}));
}

TEST(RecentRing, ZeroCapacityIsRefusedWithAReason) {
  try {
    RecentRing<int> ring(0);
    ADD_FAILURE() << "a ring of capacity 0 was made";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("capacity"), std::string::npos) << e.what();
  }
}

// 8 writers push (writer, 0..N-1) while a reader snapshots: every snapshot stays within the
// capacity with each writer's values increasing; at the end the ring holds the last
// `capacity` pushes, so each writer present has a run of consecutive values ending at N-1.
TEST(RecentRing, ConcurrentWritersStayBoundedAndOrdered) {
  constexpr int kWriters = 8, kPushes = 20000;
  constexpr std::size_t kCapacity = 100;
  RecentRing<std::pair<int, int>> ring(kCapacity);
  auto eachWriterIncreases = [](const std::vector<std::pair<int, int>>& values) {
    std::vector<int> last(kWriters, -1);
    for (const auto& [writer, seq] : values) {
      if (seq <= last[writer]) return false;
      last[writer] = seq;
    }
    return true;
  };

  std::atomic<int> writers_left{kWriters};
  std::atomic<int> bad_snapshots{0}, snapshots{0};
  std::thread reader([&] {
    do {
      const auto values = ring.snapshot();
      ++snapshots;
      if (values.size() > kCapacity || !eachWriterIncreases(values)) ++bad_snapshots;
    } while (writers_left.load() > 0);
  });
  std::vector<std::thread> writers;
  for (int w = 0; w < kWriters; ++w)
    writers.emplace_back([&, w] {
      while (snapshots.load() == 0) std::this_thread::yield();  // the reader reads while they write
      for (int i = 0; i < kPushes; ++i) ring.push({w, i});
      --writers_left;
    });
  for (auto& t : writers) t.join();
  reader.join();

  EXPECT_EQ(bad_snapshots.load(), 0) << "of " << snapshots.load() << " snapshots";
  EXPECT_EQ(ring.pushed(), static_cast<std::uint64_t>(kWriters) * kPushes);
  const auto values = ring.snapshot();
  ASSERT_EQ(values.size(), kCapacity);
  EXPECT_TRUE(eachWriterIncreases(values));
  std::vector<std::vector<int>> by_writer(kWriters);
  for (const auto& [writer, seq] : values) by_writer[writer].push_back(seq);
  for (int w = 0; w < kWriters; ++w) {
    const std::vector<int>& seqs = by_writer[w];
    if (seqs.empty()) continue;  // all of this writer's pushes came before the last 100
    EXPECT_EQ(seqs.back(), kPushes - 1) << "writer " << w;
    for (std::size_t i = 1; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], seqs[i - 1] + 1) << "writer " << w;
  }
}

}  // namespace
}  // namespace robodiff::testing
