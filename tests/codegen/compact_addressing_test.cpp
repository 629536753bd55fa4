// Compact addressing (core/codegen/src/compact_addressing.hpp): a large function's parts
// reach their arrays through base pointers within a one-byte displacement, and their
// constants through a table, in a body that takes them as restrict parameters. The plan
// keeps every element behind one pointer (what restrict promises the compiler); the
// generated code computes what the graph computes, with far fewer four-byte
// displacements than the same function addressed plainly, and (having no lane pairs) in
// parts of half the split threshold.
#include <gtest/gtest.h>

#include <regex>
#include <set>

#include "codegen_fixtures.hpp"
#include "compact_addressing.hpp"
#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::codegen {
namespace {

using namespace testing;
using detail::CompactAddressing;
using robodiff::testing::TempDir;

// The pointer an access is printed through: "b2" of "b2[-3]" or "b2 + 4", "w" of "w[35]".
std::string pointerOf(const std::string& access) { return access.substr(0, access.find_first_of("[ ")); }

// The offset an access is printed with, in elements.
long offsetOf(const std::string& access) {
  const std::size_t at = access.find_first_of("[+-");
  const long d = std::stol(access.substr(access.find_first_of("-0123456789", at + 1)));
  return access[at] == '-' ? -std::labs(d) : d;
}

// The threshold is for a 32 KiB instruction cache; twice the cache, twice the code.
TEST(CompactAddressing, TheThresholdScalesWithTheInstructionCache) {
  EXPECT_EQ(compactAddressingFrom(32768), kCompactAddressingFrom);
  EXPECT_EQ(compactAddressingFrom(65536), 2 * kCompactAddressingFrom);
  EXPECT_EQ(compactAddressingFrom(0), kCompactAddressingFrom);  // unknown
}

TEST(CompactAddressing, ElementsPastAByteAreReachedThroughABaseWithinIt) {
  CompactAddressing a;
  for (int pass = 0; pass < 2; ++pass) {
    for (std::uint32_t k = 300; k < 332; ++k)
      for (int use = 0; use < 3; ++use) a.element("w", k);
    a.element("w", 3);
    a.element("o1", 900);  // used once: not worth a register
    if (pass == 0) a.plan();
  }
  std::set<std::string> bases;
  for (std::uint32_t k = 300; k < 332; ++k) {
    const std::string access = a.element("w", k);
    bases.insert(pointerOf(access));
    EXPECT_GE(offsetOf(access), -16) << access;
    EXPECT_LE(offsetOf(access), 15) << access;
  }
  EXPECT_EQ(bases, std::set<std::string>{"b0"});  // 32 elements: one window
  EXPECT_EQ(a.element("w", 3), "w[3]");
  EXPECT_EQ(a.element("o1", 900), "o1[900]");
  ASSERT_EQ(a.parameters(), std::vector<std::string>{"double* restrict b0"});
  EXPECT_EQ(a.arguments("t"), std::vector<std::string>{"w + " + std::to_string(300 + 16)});
}

TEST(CompactAddressing, NoWiderAccessCrossesAWindowsEdge) {
  // Elements 200..263 used often, with pairs and four-zero stores over them, some across
  // where windows of 32 from the first element would end (231 | 232, 263 | 264): every
  // element must be printed through one pointer only, whatever access reaches it.
  const std::vector<std::uint32_t> pairs = {199, 208, 231, 240}, quads = {214, 229, 262};
  CompactAddressing a;
  for (std::uint32_t k = 200; k < 264; ++k)
    for (int use = 0; use < 4; ++use) a.element("w", k);
  for (std::uint32_t k : pairs) a.address("w", k, 2);
  for (std::uint32_t k : quads) a.address("w", k, 4);
  a.plan();
  EXPECT_GE(a.parameters().size(), 2u);
  std::map<std::uint32_t, std::string> pointer;  // element -> the pointer that reaches it
  auto reach = [&](std::uint32_t k, const std::string& access) {
    auto [it, fresh] = pointer.emplace(k, pointerOf(access));
    EXPECT_EQ(it->second, pointerOf(access)) << "element " << k << " through two pointers";
  };
  for (std::uint32_t k = 200; k < 264; ++k) reach(k, a.element("w", k));
  for (std::uint32_t k : pairs)
    for (std::uint32_t i = 0; i < 2; ++i) reach(k + i, a.address("w", k, 2));
  for (std::uint32_t k : quads)
    for (std::uint32_t i = 0; i < 4; ++i) reach(k + i, a.address("w", k, 4));
}

TEST(CompactAddressing, AnArrayClearedWholeKeepsItsOwnPointer) {
  CompactAddressing a;
  for (std::uint32_t k = 40; k < 72; ++k)
    for (int use = 0; use < 4; ++use) a.element("o0", k);
  a.whole("o0", 500);  // a memset of the block
  a.plan();
  EXPECT_TRUE(a.parameters().empty());
  EXPECT_EQ(a.element("o0", 50), "o0[50]");
}

TEST(CompactAddressing, ConstantsGoToATableMostUsedFirstButPowersOfTwoStayLiterals) {
  CompactAddressing a;
  for (int use = 0; use < 5; ++use) a.constant("0.316");
  a.constant("-9.81");
  a.constant("0.5");
  a.constant("-2.0");
  a.constant("0.0");
  a.plan();
  EXPECT_EQ(a.constant("0.316"), "k0[-16]");
  EXPECT_EQ(a.constant("-9.81"), "k0[-15]");
  EXPECT_EQ(a.constant("0.5"), "0.5");
  EXPECT_EQ(a.constant("-2.0"), "-2.0");
  EXPECT_EQ(a.constant("0.0"), "0.0");
  EXPECT_EQ(a.table("t"), "static const double t[16] = {0.316, -9.81, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, "
                          "0.0, 0.0, 0.0, 0.0, 0.0, 0.0};\n");
  EXPECT_EQ(a.arguments("t"), std::vector<std::string>{"t + 16"});
}

// Memory operands off an array's pointer (not rip, not the stack's) with a displacement
// past one byte.
std::size_t longDisplacements(const std::string& disassembly) {
  static const std::regex operand(R"((-?)0x([0-9a-f]+)\(%r(?!ip|sp))");
  std::size_t n = 0;
  for (auto it = std::sregex_iterator(disassembly.begin(), disassembly.end(), operand); it != std::sregex_iterator();
       ++it)
    if (std::stoul((*it)[2].str(), nullptr, 16) > 127) ++n;
  return n;
}

TEST(CompactAddressing, ALargeSplitFunctionComputesTheSameWithFewerLongDisplacements) {
  Graph g;
  const FunctionDefinition f = randomFunction(g, "r", 11, 2000);
  TempDir dir;
  CompilerOptions compiler;
  compiler.native = true;
  std::map<bool, std::size_t> long_displacements;
  std::map<bool, std::uint32_t> parts_of;
  for (bool compact : {false, true}) {
    CodegenOptions options;
    options.split_threshold = 400;
    options.compact_addressing_from = compact ? 1 : 0;
    const GeneratedLibrary generated = generateLibrary(g, {f}, options);
    std::string sources;
    for (const SourceFile& s : generated.sources) sources += s.text;
    EXPECT_EQ(sources.find("_body(") != std::string::npos, compact);
    const std::string name = compact ? "compact" : "plain";
    const auto path = compileLibrary(generated, dir / (name + ".so"), compiler).library;
    const LoadedLibrary library = LoadedLibrary::open(path);
    const CompiledFunction& fn = library.function("r");
    std::vector<double> work(fn.workSize() + 1);
    for (std::uint32_t seed = 1; seed <= 3; ++seed) {
      const auto in = randomInputs(f, 1, seed);
      const auto expected = reference(g, f, in, 0);
      auto out = outputBuffers(f, 1);
      fn.evaluate(pointers(in, f).data(), pointers(out, f).data(), work.data());
      for (std::size_t b = 0; b < expected.size(); ++b)
        for (std::size_t i = 0; i < expected[b].size(); ++i)
          EXPECT_TRUE(closeRelative(out[b][i], expected[b][i], 1e-12)) << name << " block " << b << " entry " << i;
    }
    const std::uint32_t parts = parts_of[compact] = generated.functions.at(0).parts;
    ASSERT_GE(parts, 4u);
    for (std::uint32_t p = 0; p < parts; ++p)
      long_displacements[compact] +=
          longDisplacements(disassembly(path, "rd_r_p" + std::to_string(p) + (compact ? "_body" : "")));
  }
  std::cout << "long displacements: " << long_displacements[false] << " plain, " << long_displacements[true]
            << " compact\n";
  // No lane pairs: the compact build is cut into parts of half the split threshold.
  EXPECT_GE(parts_of[true], 2 * parts_of[false] - 1);
  EXPECT_GT(long_displacements[false], 100u);
  // 1,426 against 2,849 with codegen 0.4.13 (sums in order of readiness; 0.4.12 had a
  // little more margin to a half).
  EXPECT_LT(10 * long_displacements[true], 6 * long_displacements[false]);
}

}  // namespace
}  // namespace robodiff::codegen
