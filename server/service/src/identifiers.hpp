#pragma once
// Ids the service makes: its instance id ("<host>:<pid>:<8 hex random>", unique per
// process start) and function ids (deterministic: the same spec on the same model is the
// same function, on every server).

#include <string>
#include <string_view>

namespace robodiff::server::detail {

std::string makeInstanceId();

// The first 32 hex digits of SHA-256(model_id + "\n" + normalized spec JSON).
std::string functionId(std::string_view model_id, std::string_view normalized_spec);

}  // namespace robodiff::server::detail
