// Fuzz target: the function-spec parser as robodiffd's GetFunction runs it
// (server/service/src/service.cpp): spec JSON -> FunctionSpec (model-function specs and
// user functions, whose expressions are parsed here too), then the normalised JSON that
// names the function (part of the cache key). A model-function spec must parse again from
// its normalised JSON to the same normalised JSON, and a user function's text must give
// the same canonical form twice: otherwise one function would get two cache keys.
//
// Expected failures are SpecError (INVALID_ARGUMENT / RESOURCE_EXHAUSTED at the service).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "robodiff/functions/function_spec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  robodiff::FunctionSpec spec;
  try {
    spec = robodiff::parseFunctionSpec(text, "spec_json");
  } catch (const robodiff::SpecError&) {
    return 0;  // refused with a message
  }
  const std::string normalized = robodiff::normalizedSpecJson(spec);
  // A user function's normalised form is its canonical terms (not a spec): parsing the
  // same text again must give it again. A model function's is a spec: it must parse.
  const std::string& again_text = spec.isUser() ? text : normalized;
  std::string again;
  try {
    again = robodiff::normalizedSpecJson(robodiff::parseFunctionSpec(again_text, "again"));
  } catch (const robodiff::SpecError& e) {
    std::fprintf(stderr, "the spec does not parse a second time: %s\n%s\n", e.what(), again_text.c_str());
    std::abort();
  }
  if (again != normalized) {
    std::fprintf(stderr, "normalising is not stable:\n%s\n%s\n", normalized.c_str(), again.c_str());
    std::abort();
  }
  return 0;
}
