// The loader: opens a library made by the code generator, checks its descriptor (ABI
// version, consistency, and what the caller expects of a function) before anything in
// it is called, and hands out its functions. The library is unloaded when the last
// LoadedLibrary or CompiledFunction referring to it is gone.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "robodiff/codegen/abi.h"

namespace robodiff::codegen {

class LoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a caller expects of a function; unset fields are not checked.
struct FunctionExpectations {
  std::string name;
  std::optional<std::vector<std::uint32_t>> input_sizes;   // doubles per input block
  std::optional<std::vector<std::uint32_t>> output_sizes;  // doubles per output block (nnz)
};

// One function of a loaded library. Same conventions as abi.h; keeps its library loaded.
class CompiledFunction {
 public:
  const robodiff_function_desc& descriptor() const { return *desc_; }
  std::string name() const { return desc_->name; }
  std::size_t workSize() const { return static_cast<std::size_t>(desc_->work_size); }
  std::size_t batchWorkSize() const { return static_cast<std::size_t>(desc_->batch_work_size); }
  std::uint32_t batchWidth() const { return desc_->batch_width; }

  void evaluate(const double* const* in, double* const* out, double* work) const { desc_->eval(in, out, work); }
  void evaluateBatch(std::uint64_t n, const double* const* in, double* const* out, double* work) const {
    desc_->eval_batch(n, in, out, work);
  }

 private:
  friend class LoadedLibrary;
  CompiledFunction(std::shared_ptr<void> handle, const robodiff_function_desc* desc)
      : handle_(std::move(handle)), desc_(desc) {}
  std::shared_ptr<void> handle_;
  const robodiff_function_desc* desc_;
};

class LoadedLibrary {
 public:
  // dlopen (RTLD_NOW | RTLD_LOCAL) and check the descriptor. Throws LoadError saying
  // what is wrong: not loadable, no descriptor, another ABI version, an inconsistent
  // descriptor.
  static LoadedLibrary open(const std::filesystem::path& path);

  const std::filesystem::path& path() const { return path_; }
  const robodiff_library_desc& descriptor() const { return *desc_; }
  std::string generatorVersion() const { return desc_->generator_version; }
  std::vector<std::string> functionNames() const;

  // The function, checked against the expectations. Throws LoadError naming what differs
  // (an unknown name lists the names there are).
  CompiledFunction function(const FunctionExpectations& expected) const;
  CompiledFunction function(std::string_view name) const {
    FunctionExpectations expected;
    expected.name = name;
    return function(expected);
  }

 private:
  LoadedLibrary(std::filesystem::path path, std::shared_ptr<void> handle, const robodiff_library_desc* desc)
      : path_(std::move(path)), handle_(std::move(handle)), desc_(desc) {}
  std::filesystem::path path_;
  std::shared_ptr<void> handle_;  // dlclose when the last user is gone
  const robodiff_library_desc* desc_;
};

}  // namespace robodiff::codegen
