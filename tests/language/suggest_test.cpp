// Closest-name suggestions: typos, transpositions, case, containment, far names, order,
// and bounded work for absurdly long names.
#include <chrono>

#include <gtest/gtest.h>

#include "robodiff/language/suggest.hpp"

namespace robodiff::language {
namespace {

using Names = std::vector<std::string>;

const Names kFrames = {"panda_link0", "panda_link1", "panda_link7", "panda_hand", "panda_leftfinger",
                       "panda_rightfinger", "world"};

TEST(Suggest, Typos) {
  EXPECT_EQ(closestNames("panda_hnd", kFrames), Names{"panda_hand"});
  EXPECT_EQ(closestNames("panda_hadn", kFrames), Names{"panda_hand"});  // a swap costs 1
  EXPECT_EQ(closestNames("wrold", kFrames), Names{"world"});
  EXPECT_EQ(closestNames("PANDA_HAND", kFrames), Names{"panda_hand"});  // case-insensitive
}

TEST(Suggest, ContainmentEitherWay) {
  EXPECT_EQ(closestNames("hand", kFrames), Names{"panda_hand"});
  EXPECT_EQ(closestNames("finger", kFrames), (Names{"panda_leftfinger", "panda_rightfinger"}));
  EXPECT_EQ(closestNames("the_world_frame", kFrames), Names{"world"});
}

TEST(Suggest, SortedByDistanceThenNameAndCapped) {
  EXPECT_EQ(closestNames("panda_link", kFrames), (Names{"panda_link0", "panda_link1", "panda_link7"}));
  EXPECT_EQ(closestNames("panda_link", kFrames, 2), (Names{"panda_link0", "panda_link1"}));
  const Names velocities = {"v_nest", "v_next", "q_next", "v_next_next", "v"};
  EXPECT_EQ(closestNames("v_nxt", velocities), (Names{"v_next", "q_next", "v_nest"}));
  EXPECT_EQ(closestNames("v_nxt", velocities, 10), (Names{"v_next", "q_next", "v_nest"}));
  EXPECT_EQ(closestNames("ab", {"abd", "abc", "abc"}), (Names{"abc", "abd"}));  // duplicates once
}

TEST(Suggest, FarNamesGiveNothing) {
  EXPECT_TRUE(closestNames("xyz", {"panda_hand", "q", "v", "tau"}).empty());
  EXPECT_TRUE(closestNames("velocity", {"torque", "position"}).empty());
  EXPECT_TRUE(closestNames("q", {"q"}).empty());  // the name itself is no suggestion
  // Containment needs at least 3 characters: 'q' is no suggestion for 'dq_ref'.
  EXPECT_TRUE(closestNames("dq_ref", {"q", "dq"}).empty());
  EXPECT_EQ(closestNames("dq_ref", {"q_ref"}), Names{"q_ref"});
  EXPECT_TRUE(closestNames("q", {}).empty());
}

TEST(Suggest, DidYouMean) {
  EXPECT_EQ(didYouMean("panda_hnd", kFrames), " (did you mean 'panda_hand'?)");
  EXPECT_EQ(didYouMean("finger", kFrames), " (did you mean 'panda_leftfinger', 'panda_rightfinger'?)");
  EXPECT_EQ(didYouMean("xyz", kFrames), "");
}

TEST(Suggest, LongNamesAreBounded) {
  Names candidates;
  for (int i = 0; i < 300; ++i) candidates.push_back("frame_" + std::to_string(i) + std::string(200, 'a'));
  candidates.push_back(std::string(300, 'a'));
  const std::string huge(10'000'000, 'a');
  const auto start = std::chrono::steady_clock::now();
  const Names names = closestNames(huge, candidates);
  EXPECT_EQ(didYouMean(huge + "b", {"a", "b"}), "");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 2.0);
  ASSERT_FALSE(names.empty());
  EXPECT_EQ(names.front(), std::string(300, 'a'));  // equal on the first 256 characters
}

TEST(Suggest, FewHundredCandidatesAreFast) {
  Names candidates;
  for (int i = 0; i < 500; ++i) candidates.push_back("joint_" + std::to_string(i) + "_position");
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 100; ++i) closestNames("joint_42_positon", candidates);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 2.0);
  EXPECT_EQ(closestNames("joint_42_positon", candidates).front(), "joint_42_position");
}

}  // namespace
}  // namespace robodiff::language
