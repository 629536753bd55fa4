// A spec's "build" object, as every JSON form of a spec writes it (the normalised spec,
// a user function's spec and its canonical form). Json is nlohmann::json (keys sorted) or
// nlohmann::ordered_json (keys in this order).
#pragma once

#include "robodiff/functions/function_spec.hpp"

namespace robodiff::detail {

template <class Json>
Json buildOptionsJson(const BuildOptions& build) {
  Json j{{"optimization", build.optimization}, {"march_native", build.march_native}, {"fast_math", build.fast_math}};
  if (!build.target.empty()) j["target"] = build.target;  // absent by default: earlier keys stay
  if (!build.batch) j["batch"] = false;                    // likewise
  return j;
}

}  // namespace robodiff::detail
