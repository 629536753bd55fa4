// The assembly's base-relative operands (asm_addressing.hpp): every token becomes its
// offset less its base's bias, on %rbp (frame) or %rbx (pool), or without a base its
// offset from %rsp or the pool's label; the biases put the reads
// within one-byte displacements where one bias can (VEX: [-128, 127]; EVEX: scaled by
// the operand's size).
#include <gtest/gtest.h>

#include <regex>
#include <stdexcept>
#include <string>

#include "asm_addressing.hpp"

namespace robodiff::codegen::detail {
namespace {

// The displacements of `base` in the text, in order.
std::vector<int> displacements(const std::string& text, const std::string& base) {
  std::vector<int> out;
  const std::regex operand("(-?[0-9]+)\\(%" + base + "\\)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), operand); it != std::sregex_iterator(); ++it)
    out.push_back(std::stoi((*it)[1]));
  return out;
}

TEST(AsmAddressing, TokensBecomeOffsetsFromTheirBases) {
  const std::string text = "\tvmulsd\t" + frameOperand(40) + ", %xmm1, %xmm2\n\tvaddsd\t" + poolOperand(32) +
                           ", %xmm2, %xmm3\n\tvmovsd\t%xmm3, " + frameOperand(1200) + "\n";
  BaseBiases biases;
  biases.frame = 100;
  biases.pool = 16;
  const std::string resolved = resolveOperands(text, biases);
  EXPECT_EQ(resolved, "\tvmulsd\t-60(%rbp), %xmm1, %xmm2\n\tvaddsd\t16(%rbx), %xmm2, %xmm3\n\tvmovsd\t%xmm3, 1100(%rbp)\n");
  EXPECT_EQ(resolveOperands("\tvaddsd\t%xmm1, %xmm2, %xmm3\n", {}), "\tvaddsd\t%xmm1, %xmm2, %xmm3\n");
  EXPECT_EQ(resolveOperands(text, BaseBiases{100, std::nullopt}),
            "\tvmulsd\t-60(%rbp), %xmm1, %xmm2\n\tvaddsd\t.LRDc0+32(%rip), %xmm2, %xmm3\n\tvmovsd\t%xmm3, 1100(%rbp)\n")
      << "no pool base: RIP-relative";
  EXPECT_EQ(resolveOperands(text, BaseBiases{}),
            "\tvmulsd\t40(%rsp), %xmm1, %xmm2\n\tvaddsd\t.LRDc0+32(%rip), %xmm2, %xmm3\n\tvmovsd\t%xmm3, 1200(%rsp)\n")
      << "no bases";
  EXPECT_THROW(resolveOperands("\tvmovsd\t@F8, %xmm0\n", biases), std::logic_error) << "an unterminated token";
}

TEST(AsmAddressing, TheBiasesPutTheReadsWithinOneByteDisplacements) {
  // VEX reads (registers below 16) 1,000-1,240 bytes into the frame, read most; one at 0.
  std::string text;
  for (int offset = 1000; offset <= 1240; offset += 8)
    for (int k = 0; k < 3; ++k) text += "\tvaddsd\t" + frameOperand(offset) + ", %xmm1, %xmm2\n";
  text += "\tvaddsd\t" + frameOperand(0) + ", %xmm1, %xmm2\n";
  const BaseBiases vex = chooseBiases(text);
  ASSERT_TRUE(vex.frame);
  EXPECT_FALSE(vex.pool);
  const std::vector<int> d = displacements(resolveOperands(text, vex), "rbp");
  for (std::size_t k = 0; k + 1 < d.size(); ++k) EXPECT_TRUE(d[k] >= -128 && d[k] <= 127) << d[k];

  // EVEX reads of doubles (a register above 15): 8-byte steps scale the range to
  // [-1024, 1016], so reads 0-1,600 bytes into the pool apart fit one bias.
  std::string evex;
  for (int offset = 0; offset <= 1600; offset += 160) evex += "\tvmulsd\t" + poolOperand(offset) + ", %xmm20, %xmm21\n";
  const BaseBiases scaled = chooseBiases(evex);
  ASSERT_TRUE(scaled.pool);
  for (int x : displacements(resolveOperands(evex, scaled), "rbx")) EXPECT_TRUE(x % 8 == 0 && x >= -1024 && x <= 1016) << x;
}

}  // namespace
}  // namespace robodiff::codegen::detail
