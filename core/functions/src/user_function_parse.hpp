// The user-function form of a spec ("inputs" / "define" / "outputs") from its JSON
// object, keys in the order written (nlohmann::ordered_json): the inputs' order is the
// order of the function's runtime blocks.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "robodiff/functions/function_spec.hpp"

namespace robodiff::detail {

// Whether a spec object is of the user form (it has "define", or outputs with "of").
bool isUserFunctionJson(const nlohmann::ordered_json& root);

// Parses and checks everything that does not need the model: names, expression syntax,
// output kinds, that every wrt names a variable input. Throws SpecError naming the
// source, the field and the value; SpecTooLarge past `limits`.
UserFunction parseUserFunction(const nlohmann::ordered_json& root, const std::string& source,
                               const UserFunctionLimits& limits = {});

// The spec's model-function-shaped view of a user function (FunctionSpec's inputs and
// outputs; user_function.hpp says how).
void fillSpecView(FunctionSpec& spec);

}  // namespace robodiff::detail
