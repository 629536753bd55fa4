#include "robodiff/language/bounded_text.hpp"
#include "robodiff/language/suggest.hpp"

#include <gtest/gtest.h>

#include <string>

namespace robodiff::language {
namespace {

TEST(BoundedText, ShortTextIsKeptWhole) {
  EXPECT_EQ(boundedText("panda_hand"), "panda_hand");
  EXPECT_EQ(quote("panda_hand"), "'panda_hand'");
  EXPECT_EQ(boundedText(std::string(kQuotedPrefixBytes, 'x')), std::string(kQuotedPrefixBytes, 'x'));
}

TEST(BoundedText, LongTextKeepsAPrefixAndItsSize) {
  const std::string huge(10 << 20, 'x');
  const std::string text = boundedText(huge);
  EXPECT_EQ(text, std::string(kQuotedPrefixBytes, 'x') + "\u2026 (10485760 bytes)");
  EXPECT_LT(quote(huge).size(), 200u);
}

TEST(BoundedText, NeverCutsAUtf8Character) {
  // 'é' is two bytes: a cut at an odd byte would split one.
  std::string accents;
  for (int i = 0; i < 100; ++i) accents += "\u00e9";
  const std::string text = boundedText(accents, 7);
  EXPECT_EQ(text, "\u00e9\u00e9\u00e9\u2026 (200 bytes)");
}

TEST(BoundedText, SuggestionsQuoteLongCandidatesShort) {
  // A candidate that contains the name is suggested; its 1 MB are not repeated.
  const std::string long_frame = "hand" + std::string(1 << 20, 'x');
  const std::string hint = didYouMean("hand", {long_frame});
  EXPECT_NE(hint.find("(1048580 bytes)"), std::string::npos) << hint.substr(0, 300);
  EXPECT_LT(hint.size(), 200u);
}

}  // namespace
}  // namespace robodiff::language
