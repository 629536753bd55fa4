#pragma once
// What every DDS transport test shares: the loopback configuration (CYCLONEDDS_URI pointing at
// deploy/cyclonedds-loopback.xml) and a DDS domain of its own per test process
// (support/dds_domain.hpp), so that parallel ctest runs never see each other's servers.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "support/dds_domain.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

inline void useLoopbackConfig() {
  const auto xml = sourceDir() / "deploy" / "cyclonedds-loopback.xml";
  ASSERT_TRUE(std::filesystem::exists(xml)) << xml;
  setenv("CYCLONEDDS_URI", ("file://" + xml.string()).c_str(), 1);
}

class DdsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { useLoopbackConfig(); }
};

// Polls `condition` every 5 ms until it holds or `timeout` passes.
template <class Condition>
bool eventually(Condition condition, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace robodiff::testing
