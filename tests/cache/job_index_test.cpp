// The jobs table of the cache's index: listing is newest first, and a limit returns just
// the newest ones (what the dashboard polls every second), in the same order.
#include <gtest/gtest.h>

#include "robodiff/cache/job_index.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::cache {
namespace {

std::vector<std::string> ids(const std::vector<JobRecord>& records) {
  std::vector<std::string> out;
  for (const JobRecord& r : records) out.push_back(r.id);
  return out;
}

TEST(JobIndex, ListsNewestFirstAndALimitKeepsTheNewest) {
  testing::TempDir dir;
  JobIndex index(dir / "cache");
  for (int k = 1; k <= 5; ++k) {
    JobRecord r;
    r.id = "job-" + std::to_string(k);
    r.kind = "trajectory";
    r.state = "QUEUED";
    r.params_json = "{}";
    r.owner = "test";
    r.submitted_ms = 1000 * k;
    index.insert(r);
  }
  EXPECT_EQ(ids(index.list()), (std::vector<std::string>{"job-5", "job-4", "job-3", "job-2", "job-1"}));
  EXPECT_EQ(ids(index.list(0)), ids(index.list()));
  EXPECT_EQ(ids(index.list(2)), (std::vector<std::string>{"job-5", "job-4"}));
  EXPECT_EQ(index.list(9).size(), 5u);
  const std::vector<JobRecord> newest = index.list(1);
  ASSERT_EQ(newest.size(), 1u);
  EXPECT_EQ(newest[0].submitted_ms, 5000);
  EXPECT_EQ(newest[0].state, "QUEUED");
}

}  // namespace
}  // namespace robodiff::cache
