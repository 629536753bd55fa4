#include "robodiff/workers/build_job.hpp"

#include <algorithm>
#include <new>

#include <nlohmann/json.hpp>

#include "robodiff/codegen/compiler.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::workers {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

// Compiler output kept in an outcome: enough for the first errors, not a megabyte of them.
constexpr std::size_t kOutputKeep = 8 * 1024;

std::string trimmed(const std::string& text) {
  if (text.size() <= kOutputKeep) return text;
  return text.substr(0, kOutputKeep) + "\n... (" + std::to_string(text.size() - kOutputKeep) + " more bytes)";
}

// --- JSON fields, checked: a missing or mistyped one is named ---

class Fields {
 public:
  Fields(const json& object, std::string where) : object_(object), where_(std::move(where)) {
    if (!object_.is_object()) throw std::invalid_argument(where_ + ": expected a JSON object");
  }

  template <typename T>
  T required(const char* name) const {
    const auto it = object_.find(name);
    if (it == object_.end()) throw std::invalid_argument(where_ + ": missing field \"" + name + "\"");
    return convert<T>(*it, name);
  }
  template <typename T>
  void optional(const char* name, T& out) const {
    const auto it = object_.find(name);
    if (it != object_.end()) out = convert<T>(*it, name);
  }
  const json& object(const char* name) const {
    const auto it = object_.find(name);
    if (it == object_.end()) throw std::invalid_argument(where_ + ": missing field \"" + name + "\"");
    return *it;
  }
  bool has(const char* name) const { return object_.contains(name); }
  std::string path(const char* name) const { return where_ + "." + name; }

 private:
  template <typename T>
  T convert(const json& value, const char* name) const {
    bool fits;
    if constexpr (std::is_same_v<T, std::string>) fits = value.is_string();
    else if constexpr (std::is_same_v<T, bool>) fits = value.is_boolean();
    else if constexpr (std::is_same_v<T, double>) fits = value.is_number();
    else if constexpr (std::is_unsigned_v<T>) fits = value.is_number_unsigned();
    else fits = value.is_number_integer();
    if (!fits) {
      const char* expected = std::is_same_v<T, std::string> ? "a string"
                             : std::is_same_v<T, bool>      ? "true or false"
                             : std::is_same_v<T, double>    ? "a number"
                             : std::is_unsigned_v<T>        ? "a non-negative integer"
                                                            : "an integer";
      throw std::invalid_argument(where_ + ": field \"" + name + "\" must be " + expected + ", not " +
                                  value.dump().substr(0, 80));
    }
    return value.get<T>();
  }

  const json& object_;
  std::string where_;
};

json parseObject(const std::string& text, const std::string& what) {
  json j = json::parse(text, nullptr, false);
  if (j.is_discarded()) throw std::invalid_argument(what + ": not valid JSON");
  if (!j.is_object()) throw std::invalid_argument(what + ": expected a JSON object");
  return j;
}

json toJson(const cache::EntryInfo& info) {
  return {{"model_hash", info.model_hash}, {"robot", info.robot},       {"function", info.function},
          {"spec", info.spec},             {"sizes", info.sizes},       {"compiler", info.compiler},
          {"build_seconds", info.build_seconds}, {"portable_key", info.portable_key}};
}

cache::EntryInfo entryInfoFromJson(const json& j, const std::string& where) {
  const Fields f(j, where);
  cache::EntryInfo info;
  f.optional("model_hash", info.model_hash);
  f.optional("robot", info.robot);
  f.optional("function", info.function);
  f.optional("spec", info.spec);
  f.optional("sizes", info.sizes);
  f.optional("compiler", info.compiler);
  f.optional("build_seconds", info.build_seconds);
  f.optional("portable_key", info.portable_key);
  return info;
}

// {"inputs": [doubles per block], "outputs": [doubles written per block]}
std::string blockSizes(const codegen::FunctionDefinition& definition) {
  json inputs = json::array(), outputs = json::array();
  for (const auto& block : definition.inputs) inputs.push_back(block.size);
  for (const auto& block : definition.outputs) outputs.push_back(block.size());
  return json{{"inputs", inputs}, {"outputs", outputs}}.dump();
}

// The sources as compiled (.c and .h, or the assembly's .s, under the build's src/), not
// the objects.
std::vector<fs::path> sourceFiles(const fs::path& src_dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(src_dir)) {
    const auto ext = entry.path().extension();
    if (entry.is_regular_file() && (ext == ".c" || ext == ".h" || ext == ".s")) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

void fail(BuildOutcome& outcome, const char* kind, const std::string& message, const std::string& output = {}) {
  outcome.ok = false;
  outcome.error_kind = kind;
  outcome.message = trimmed(message);
  outcome.compiler_output = trimmed(output);
}

const char* compileErrorKind(codegen::CompileError::Kind kind) {
  using Kind = codegen::CompileError::Kind;
  switch (kind) {
    case Kind::CompilerFailed: return "compile_failed";
    case Kind::Timeout: return "compile_timeout";
    case Kind::MemoryLimit: return "compile_memory";
    case Kind::CannotRun: return "compiler_missing";
    case Kind::Io: return "internal";
  }
  return "internal";
}

json urdfLimitsJson(const UrdfLimits& l) {
  return {{"max_bytes", l.max_bytes},           {"max_depth", l.max_depth},
          {"max_elements", l.max_elements},     {"max_links", l.max_links},
          {"max_joints", l.max_joints},         {"max_name_length", l.max_name_length},
          {"max_attribute_length", l.max_attribute_length}};
}

UrdfLimits urdfLimitsFromJson(const json& j, const std::string& where) {
  const Fields f(j, where);
  UrdfLimits l;
  f.optional("max_bytes", l.max_bytes);
  f.optional("max_depth", l.max_depth);
  f.optional("max_elements", l.max_elements);
  f.optional("max_links", l.max_links);
  f.optional("max_joints", l.max_joints);
  f.optional("max_name_length", l.max_name_length);
  f.optional("max_attribute_length", l.max_attribute_length);
  return l;
}

}  // namespace

// --- codecs ---

std::string toJson(const BuildRequest& r) {
  json j = {{"urdf", r.urdf},
            {"urdf_source", r.urdf_source},
            {"urdf_limits", urdfLimitsJson(r.urdf_limits)},
            {"floating_base", r.floating_base},
            {"spec", r.spec},
            {"spec_source", r.spec_source},
            {"function_name", r.function_name},
            {"compiler", r.compiler},
            {"compiler_memory_limit_bytes", r.compiler_memory_limit_bytes},
            {"compiler_timeout_ms", static_cast<std::uint64_t>(std::max<std::int64_t>(r.compiler_timeout.count(), 0))},
            {"compiler_jobs", r.compiler_jobs},
            {"cache_dir", r.cache_dir},
            {"cache_budget_bytes", r.cache_budget_bytes},
            {"claim", {{"key", r.claim.key}, {"owner", r.claim.owner}}},
            {"info", toJson(r.info)}};
  return j.dump();
}

BuildRequest buildRequestFromJson(const std::string& json_text) {
  const json j = parseObject(json_text, "build request");
  const Fields f(j, "build request");
  BuildRequest r;
  r.urdf = f.required<std::string>("urdf");
  r.spec = f.required<std::string>("spec");
  r.cache_dir = f.required<std::string>("cache_dir");
  f.optional("urdf_source", r.urdf_source);
  if (f.has("urdf_limits")) r.urdf_limits = urdfLimitsFromJson(f.object("urdf_limits"), f.path("urdf_limits"));
  f.optional("floating_base", r.floating_base);
  f.optional("spec_source", r.spec_source);
  f.optional("function_name", r.function_name);
  f.optional("compiler", r.compiler);
  f.optional("compiler_memory_limit_bytes", r.compiler_memory_limit_bytes);
  std::uint64_t timeout_ms = static_cast<std::uint64_t>(r.compiler_timeout.count());
  f.optional("compiler_timeout_ms", timeout_ms);
  r.compiler_timeout = std::chrono::milliseconds(timeout_ms);
  f.optional("compiler_jobs", r.compiler_jobs);
  f.optional("cache_budget_bytes", r.cache_budget_bytes);
  const Fields claim(f.object("claim"), f.path("claim"));
  r.claim.key = claim.required<std::string>("key");
  r.claim.owner = claim.required<std::string>("owner");
  if (f.has("info")) r.info = entryInfoFromJson(f.object("info"), f.path("info"));
  return r;
}

std::string toJson(const BuildOutcome& o) {
  json j = {{"ok", o.ok},       {"error_kind", o.error_kind}, {"message", o.message},
            {"key", o.key},     {"seconds", o.seconds},       {"operations", o.operations},
            {"library_bytes", o.library_bytes}};
  if (!o.compiler_output.empty()) j["compiler_output"] = o.compiler_output;
  return j.dump();
}

BuildOutcome buildOutcomeFromJson(const std::string& json_text) {
  const json j = parseObject(json_text, "build outcome");
  const Fields f(j, "build outcome");
  BuildOutcome o;
  o.ok = f.required<bool>("ok");
  f.optional("error_kind", o.error_kind);
  f.optional("message", o.message);
  f.optional("compiler_output", o.compiler_output);
  f.optional("key", o.key);
  f.optional("seconds", o.seconds);
  f.optional("operations", o.operations);
  f.optional("library_bytes", o.library_bytes);
  return o;
}

// --- preparing and running a build ---

namespace {

// The prepared build's library options, within the limits the requester set.
LibraryOptions workerLibraryOptions(const cache::PreparedBuild& prepared, const BuildRequest& request) {
  LibraryOptions options = prepared.options;
  options.compiler.memory_limit_bytes = request.compiler_memory_limit_bytes;
  options.compiler.timeout = request.compiler_timeout;
  options.compiler.jobs = request.compiler_jobs;
  return options;
}

// The cache row of the built library: what the requester said, completed from what this
// worker prepared and built.
cache::EntryInfo publishedInfo(const BuildRequest& request, const cache::PreparedBuild& prepared,
                               const GeneratedFunctionLibrary& generated, double build_seconds) {
  cache::EntryInfo info = request.info;
  const cache::EntryInfo& known = prepared.info;
  if (info.model_hash.empty()) info.model_hash = known.model_hash;
  if (info.robot.empty()) info.robot = known.robot;
  if (info.function.empty()) info.function = known.function;
  if (info.spec.empty()) info.spec = known.spec;
  if (info.compiler.empty()) info.compiler = known.compiler;
  info.portable_key = known.portable_key;  // from the identity this worker checked the key against
  info.sizes = blockSizes(generated.built.definition);
  info.build_seconds = build_seconds;
  return info;
}

// The exception being handled, as the outcome's error kind and message.
void failWithCurrentException(BuildOutcome& outcome) {
  try {
    throw;
  } catch (const ModelError& e) {
    fail(outcome, "invalid_urdf", e.what());
  } catch (const SpecError& e) {
    fail(outcome, "invalid_spec", e.what());
  } catch (const symbolic::GraphTooLarge& e) {
    fail(outcome, "graph_too_large", e.what());
  } catch (const codegen::CompileError& e) {
    fail(outcome, compileErrorKind(e.kind()), e.what(), e.compilerOutput());
  } catch (const cache::CacheError& e) {
    fail(outcome, "cache", e.what());
  } catch (const std::bad_alloc&) {
    fail(outcome, "internal",
         "out of memory while building (std::bad_alloc): the worker's address-space limit is too low for this "
         "function, or the machine is out of memory");
  } catch (const std::exception& e) {
    fail(outcome, "internal", e.what());
  } catch (...) {
    fail(outcome, "internal", "unknown exception");
  }
}

}  // namespace

BuildOutcome executeBuild(const BuildRequest& request, const std::function<void(const std::string& stage)>& progress) {
  const auto started = Clock::now();
  auto stage = [&](const char* name) {
    if (progress) progress(name);
  };
  BuildOutcome outcome;
  outcome.key = request.claim.key;
  fs::path staging;  // this build's directory, removed when the build fails
  try {
    stage("model");
    const Model model = loadUrdfString(request.urdf, request.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed,
                                       request.urdf_source.empty() ? "<string>" : request.urdf_source,
                                       request.urdf_limits);
    const FunctionSpec spec = parseFunctionSpec(request.spec, request.spec_source.empty() ? "<spec>" : request.spec_source);
    const cache::PreparedBuild prepared =
        cache::prepareBuild(model, canonicalHash(model), spec, request.function_name, request.compiler);
    if (prepared.key != request.claim.key) {
      fail(outcome, "internal",
           "the worker computed the key " + prepared.key + " for this build but the claim is for " +
               request.claim.key + ": the requester and the worker disagree on the build's identity (" +
               "different robodiff versions, or a different compiler or $CC?)");
      return outcome;
    }
    cache::CacheOptions cache_options;
    cache_options.budget_bytes = request.cache_budget_bytes;
    cache_options.create = false;  // the requester made it; a missing one is an error
    cache::Cache cache = cache::Cache::open(request.cache_dir, cache_options);
    staging = cache.stagingDir(request.claim);

    LibraryOptions options = workerLibraryOptions(prepared, request);
    options.on_stage = stage;
    const GeneratedFunctionLibrary generated = generateFunctionLibrary(model, spec, staging / "build", options);

    stage("publish");
    const double build_seconds = std::chrono::duration<double>(Clock::now() - started).count();
    cache::ArtifactFiles files;
    files.library = generated.library;
    files.description = generated.description;
    files.sources = sourceFiles(generated.library.parent_path() / "src");
    cache.publish(request.claim, publishedInfo(request, prepared, generated, build_seconds), files);

    outcome.ok = true;
    outcome.operations = generated.info.operations;
    outcome.library_bytes = generated.library_bytes;
  } catch (...) {
    failWithCurrentException(outcome);
  }
  if (!outcome.ok && !staging.empty()) {
    std::error_code ec;  // the claim is the requester's to abandon; the files are ours
    fs::remove_all(staging, ec);
  }
  outcome.seconds = std::chrono::duration<double>(Clock::now() - started).count();
  return outcome;
}

}  // namespace robodiff::workers
