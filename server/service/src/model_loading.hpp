#pragma once
// LoadModel's input checks and the model it makes: the URDF's size, options_json (a JSON
// object; every key must be known), the URDF itself (ModelError's message names the
// line, the element and the value), the canonical hash as the model id.

#include <cstddef>
#include <memory>

#include "model_entry.hpp"
#include "robodiff/model/urdf_limits.hpp"
#include "robodiff/schema/messages.hpp"

namespace robodiff::server::detail {

// Keys options_json may have.
//   "source_name": string  the name the URDF goes by in messages (default "<urdf>")
struct ModelOptions {
  std::string source_name = "<urdf>";
};

// INVALID_ARGUMENT naming the problem (not JSON, not an object, an unknown key with the
// known ones, a value of the wrong type).
Status parseModelOptions(const std::string& options_json, ModelOptions& options);

// OK and `entry` (references and functions 0); RESOURCE_EXHAUSTED naming the limit when
// the URDF exceeds max_urdf_bytes or `limits`; INVALID_ARGUMENT saying why the model
// cannot be loaded otherwise (physically invalid: naming the link).
Status loadModelEntry(const rpc::LoadModelRequest& request, std::size_t max_urdf_bytes, const UrdfLimits& limits,
                      std::shared_ptr<ModelEntry>& entry);

}  // namespace robodiff::server::detail
