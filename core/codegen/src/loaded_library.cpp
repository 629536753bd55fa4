#include "robodiff/codegen/loaded_library.hpp"

#include <dlfcn.h>

namespace robodiff::codegen {
namespace {

std::string sizesText(const std::vector<std::uint32_t>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

// Checks everything a caller relies on before calling into the library.
void checkFunction(const std::string& where, const robodiff_function_desc& f) {
  auto fail = [&](const std::string& what) { throw LoadError(where + ": " + what); };
  if (!f.name) fail("a function has no name");
  if (!f.eval || !f.eval_batch) fail("function '" + std::string(f.name) + "' has no entry point");
  if (f.batch_width < 1) fail("function '" + std::string(f.name) + "' has batch width 0");
  if (f.n_inputs > 0 && !f.inputs) fail("function '" + std::string(f.name) + "' has no input table");
  if (f.n_outputs == 0 || !f.outputs) fail("function '" + std::string(f.name) + "' has no outputs");
  for (std::uint32_t i = 0; i < f.n_inputs; ++i)
    if (!f.inputs[i].name) fail("function '" + std::string(f.name) + "': input block " + std::to_string(i) + " has no name");
  for (std::uint32_t j = 0; j < f.n_outputs; ++j) {
    const robodiff_output_desc& o = f.outputs[j];
    const std::string what = "function '" + std::string(f.name) + "', output " + std::to_string(j) + ": ";
    if (!o.name) fail(what + "no name");
    if (o.kind == ROBODIFF_OUTPUT_DENSE) {
      if (static_cast<std::uint64_t>(o.rows) * o.cols != o.nnz) fail(what + "dense but nnz != rows * cols");
    } else if (o.kind == ROBODIFF_OUTPUT_SPARSE) {
      if (!o.row_ptr || (o.nnz > 0 && !o.col_idx)) fail(what + "sparse without a CSR pattern");
      if (o.row_ptr[0] != 0 || o.row_ptr[o.rows] != o.nnz) fail(what + "CSR row pointers do not span the nonzeros");
      for (std::uint32_t r = 0; r < o.rows; ++r)
        if (o.row_ptr[r] > o.row_ptr[r + 1]) fail(what + "CSR row pointers decrease");
      for (std::uint32_t k = 0; k < o.nnz; ++k)
        if (o.col_idx[k] >= o.cols) fail(what + "CSR column index out of range");
    } else {
      fail(what + "unknown kind " + std::to_string(o.kind));
    }
  }
}

}  // namespace

LoadedLibrary LoadedLibrary::open(const std::filesystem::path& path) {
  dlerror();
  void* raw = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!raw) {
    const char* why = dlerror();
    throw LoadError("cannot load " + path.string() + ": " + (why ? why : "dlopen failed"));
  }
  std::shared_ptr<void> handle(raw, [](void* h) { dlclose(h); });
  const auto* desc = static_cast<const robodiff_library_desc*>(dlsym(raw, ROBODIFF_LIBRARY_SYMBOL));
  const std::string where = path.string();
  if (!desc)
    throw LoadError(where + " is not a robodiff library: it does not export '" ROBODIFF_LIBRARY_SYMBOL "'");
  if (desc->abi_version != ROBODIFF_ABI_VERSION)
    throw LoadError(where + " was generated for robodiff ABI version " + std::to_string(desc->abi_version) +
                    ", this loader reads version " + std::to_string(ROBODIFF_ABI_VERSION) + ": regenerate it");
  if (desc->descriptor_size != sizeof(robodiff_library_desc))
    throw LoadError(where + ": the descriptor has " + std::to_string(desc->descriptor_size) + " bytes, expected " +
                    std::to_string(sizeof(robodiff_library_desc)) + " (ABI version " +
                    std::to_string(ROBODIFF_ABI_VERSION) + "): a mismatched build");
  if (!desc->generator_version) throw LoadError(where + ": the descriptor names no generator version");
  if (desc->n_functions == 0 || !desc->functions) throw LoadError(where + ": the library holds no functions");
  for (std::uint32_t i = 0; i < desc->n_functions; ++i) checkFunction(where, desc->functions[i]);
  return LoadedLibrary(path, std::move(handle), desc);
}

std::vector<std::string> LoadedLibrary::functionNames() const {
  std::vector<std::string> names;
  for (std::uint32_t i = 0; i < desc_->n_functions; ++i) names.emplace_back(desc_->functions[i].name);
  return names;
}

CompiledFunction LoadedLibrary::function(const FunctionExpectations& expected) const {
  const robodiff_function_desc* found = nullptr;
  for (std::uint32_t i = 0; i < desc_->n_functions; ++i)
    if (expected.name == desc_->functions[i].name) found = &desc_->functions[i];
  const std::string where = path_.string();
  if (!found) {
    std::string names;
    for (const auto& n : functionNames()) names += (names.empty() ? "'" : ", '") + n + "'";
    throw LoadError(where + " has no function '" + expected.name + "' (it has " + names + ")");
  }
  const robodiff_function_desc& f = *found;
  if (expected.input_sizes) {
    std::vector<std::uint32_t> got;
    for (std::uint32_t i = 0; i < f.n_inputs; ++i) got.push_back(f.inputs[i].size);
    if (got != *expected.input_sizes)
      throw LoadError(where + ": function '" + expected.name + "' takes input blocks of sizes " + sizesText(got) +
                      ", expected " + sizesText(*expected.input_sizes));
  }
  if (expected.output_sizes) {
    std::vector<std::uint32_t> got;
    for (std::uint32_t j = 0; j < f.n_outputs; ++j) got.push_back(f.outputs[j].nnz);
    if (got != *expected.output_sizes)
      throw LoadError(where + ": function '" + expected.name + "' writes output blocks of sizes " + sizesText(got) +
                      ", expected " + sizesText(*expected.output_sizes));
  }
  return CompiledFunction(handle_, found);
}

}  // namespace robodiff::codegen
