// codegenOptionsFor: what a spec's build options change in code generation. Code built
// for this CPU (-march=native) is addressed compactly from the size this CPU's
// instruction cache holds; for a named level or a generic target, from the 32 KiB one's.
#include <gtest/gtest.h>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/functions/function_library.hpp"

namespace robodiff {
namespace {

BuildOptions buildFor(bool native, const std::string& target = "") {
  BuildOptions build;
  build.march_native = native;
  build.target = target;
  return build;
}

TEST(CodegenOptions, CodeForThisCpuIsAddressedCompactlyFromWhatItsInstructionCacheHolds) {
  const codegen::CodegenOptions base = LibraryOptions::defaultCodegenOptions();
  EXPECT_EQ(codegenOptionsFor(buildFor(true), base).compact_addressing_from,
            codegen::compactAddressingFrom(codegen::hostInstructionCacheBytes()));
  EXPECT_EQ(codegenOptionsFor(buildFor(false), base).compact_addressing_from, codegen::kCompactAddressingFrom);
  EXPECT_EQ(codegenOptionsFor(buildFor(true, "x86-64-v3"), base).compact_addressing_from,
            codegen::kCompactAddressingFrom);
}

TEST(CodegenOptions, AThresholdSetByTheCallerIsKept) {
  codegen::CodegenOptions base = LibraryOptions::defaultCodegenOptions();
  base.compact_addressing_from = 0;  // never
  EXPECT_EQ(codegenOptionsFor(buildFor(true), base).compact_addressing_from, 0u);
}

TEST(CodegenOptions, AnUnbatchedBuildHasOneLane) {
  BuildOptions build = buildFor(true);
  build.batch = false;
  EXPECT_EQ(codegenOptionsFor(build, LibraryOptions::defaultCodegenOptions()).batch_width, 1u);
  build.batch = true;
  EXPECT_EQ(codegenOptionsFor(build, LibraryOptions::defaultCodegenOptions()).batch_width, 0u);
}

}  // namespace
}  // namespace robodiff
