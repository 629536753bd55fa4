#include "model_loading.hpp"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "robodiff/language/bounded_text.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::server::detail {
namespace {
constexpr std::size_t kMaxSourceNameBytes = 256;  // options_json's source_name
constexpr std::size_t kMaxModelErrorBytes = 1024;
}  // namespace

Status parseModelOptions(const std::string& options_json, ModelOptions& options) {
  if (options_json.find_first_not_of(" \t\r\n") == std::string::npos) return {};
  const nlohmann::json j = nlohmann::json::parse(options_json, nullptr, false);
  if (j.is_discarded())
    return {StatusCode::InvalidArgument, "options_json is not valid JSON: " + language::boundedText(options_json)};
  if (!j.is_object())
    return {StatusCode::InvalidArgument,
            "options_json must be a JSON object ({\"source_name\": ...}), not " + language::boundedText(j.dump())};
  for (const auto& [key, value] : j.items()) {
    if (key == "source_name") {
      if (!value.is_string())
        return {StatusCode::InvalidArgument,
                "options_json: \"source_name\" must be a string, not " + language::boundedText(value.dump())};
      if (value.get_ref<const std::string&>().size() > kMaxSourceNameBytes)
        return {StatusCode::InvalidArgument, "options_json: \"source_name\" is " +
                                                 std::to_string(value.get_ref<const std::string&>().size()) +
                                                 " bytes, past the limit of " + std::to_string(kMaxSourceNameBytes)};
      options.source_name = value.get<std::string>();
    } else {
      return {StatusCode::InvalidArgument,
              "options_json: unknown key \"" + language::boundedText(key) + "\" (known keys: \"source_name\")"};
    }
  }
  return {};
}

Status loadModelEntry(const rpc::LoadModelRequest& request, std::size_t max_urdf_bytes, const UrdfLimits& limits,
                      std::shared_ptr<ModelEntry>& entry) {
  if (request.urdf.size() > max_urdf_bytes)
    return {StatusCode::ResourceExhausted,
            "the URDF is " + std::to_string(request.urdf.size()) +
                " bytes, more than this server accepts (max_urdf_bytes = " + std::to_string(max_urdf_bytes) + ")"};
  if (request.urdf.empty()) return {StatusCode::InvalidArgument, "the URDF is empty: send the robot's URDF text"};
  ModelOptions options;
  if (Status s = parseModelOptions(request.options_json, options); !s.ok()) return s;

  auto e = std::make_shared<ModelEntry>();
  try {
    UrdfLimits capped = limits;
    capped.max_bytes = std::min<std::uint64_t>(capped.max_bytes, max_urdf_bytes);
    Model model = loadUrdfString(request.urdf, request.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed,
                                 options.source_name, capped, PhysicsCheck::Dynamic);
    e->id = canonicalHash(model);
    e->joint_names = model.jointNames();
    e->frame_names = model.frameNames();
    e->model = std::make_shared<const Model>(std::move(model));
  } catch (const ModelTooLarge& error) {
    return {StatusCode::ResourceExhausted, language::boundedText(error.what(), kMaxModelErrorBytes)};
  } catch (const ModelError& error) {
    return {StatusCode::InvalidArgument, language::boundedText(error.what(), kMaxModelErrorBytes)};
  } catch (const std::exception& error) {
    return {StatusCode::InvalidArgument,
            language::boundedText(options.source_name + ": the URDF cannot be loaded: " + error.what(),
                                  kMaxModelErrorBytes)};
  }
  e->urdf = request.urdf;
  e->source_name = options.source_name;
  e->floating_base = request.floating_base;
  entry = std::move(e);
  return {};
}

}  // namespace robodiff::server::detail
