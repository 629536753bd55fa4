// The builder of user functions (buildFunction dispatches here for a spec of the user
// form): see user_function_builder.cpp and docs/function-language.md.
#pragma once

#include "robodiff/functions/function_builder.hpp"

namespace robodiff::detail {

BuiltFunction buildUserFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options);

// Whether any define or output of `f` calls the primitive `name`.
bool callsPrimitive(const UserFunction& f, const std::string& name);

}  // namespace robodiff::detail
