#pragma once
// The models and functions loaded, with their references: LoadModel and GetFunction
// take one for their caller, Release gives back one of the caller's own (holders.hpp). A
// function keeps its model loaded; a function without references is unloaded
// (evaluations in flight keep their evaluator alive).
// Lookups by id take a shared lock (evaluation's hot path); changes take it exclusively.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "function_entry.hpp"
#include "model_entry.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::server::detail {

struct StringHash {
  using is_transparent = void;
  std::size_t operator()(std::string_view s) const noexcept { return std::hash<std::string_view>{}(s); }
};

// What one caller (CallContext::caller, see service.cpp) may hold at once: models and
// functions it has loaded and not released (docs/limits.md, "Per-client quotas").
struct ClientQuotas {
  std::size_t max_models = SIZE_MAX;
  std::size_t max_functions = SIZE_MAX;
};

class Registry {
 public:
  explicit Registry(ClientQuotas quotas = {}) : quotas_(quotas) {}

  struct Added {
    std::shared_ptr<ModelEntry> model;        // addModel
    std::shared_ptr<FunctionEntry> function;  // addFunction
    bool created = false;                     // new, not another reference to a loaded one
    std::uint32_t references = 0;             // after this one
  };

  // A reference to the model with candidate->id: the loaded one, or the candidate when
  // none is (RESOURCE_EXHAUSTED when max_models are loaded).
  Status addModel(std::shared_ptr<ModelEntry> candidate, std::size_t max_models, const std::string& caller,
                  Added& added);
  // A reference to function `function_id` of model `model_id`: the loaded one, or the
  // one `make` creates (NOT_FOUND for an unknown model, RESOURCE_EXHAUSTED past
  // max_functions).
  using MakeFunction =
      std::function<std::shared_ptr<FunctionEntry>(std::shared_ptr<const ModelEntry>, std::uint64_t sequence)>;
  Status addFunction(std::string_view model_id, const std::string& function_id, std::size_t max_functions,
                     const MakeFunction& make, const std::string& caller, Added& added);

  std::shared_ptr<FunctionEntry> findFunction(std::string_view function_id) const;
  std::shared_ptr<ModelEntry> findModel(std::string_view model_id) const;

  struct Released {
    std::uint32_t references_left = 0;
    std::shared_ptr<FunctionEntry> function_unloaded;  // its last reference went
    std::shared_ptr<ModelEntry> model_unloaded;        // unloaded with it, or by itself
    bool was_function = false;
    bool forced = false;  // an operator dropped every caller's references
  };
  // Drops one of the caller's references. NOT_FOUND for an id that is not loaded or has no
  // references left; PERMISSION_DENIED when only other callers hold it, unless the caller
  // is an operator: then every reference goes (the entry is unloaded).
  Status release(std::string_view id, const Caller& caller, Released& released);

  // Unloads `function` if it is the one loaded under its id (a function that failed:
  // it holds no slot, whatever references clients took). True when it was unloaded.
  bool dropFailed(const std::shared_ptr<FunctionEntry>& function, Released& released);

  // Loaded functions in order of creation; those of one model when model_id is set, those
  // `holder` holds when it is set.
  std::vector<std::shared_ptr<FunctionEntry>> functions(std::optional<std::string_view> model_id = std::nullopt,
                                                        std::optional<std::string_view> holder = std::nullopt) const;
  // Snapshots with the counts the mutex guards (for the dashboard).
  struct ModelView {
    std::shared_ptr<const ModelEntry> model;
    std::uint32_t references = 0, functions = 0;
  };
  struct FunctionView {
    std::shared_ptr<const FunctionEntry> function;
    std::uint32_t references = 0;
  };
  std::vector<ModelView> modelViews() const;        // by id
  std::vector<FunctionView> functionViews() const;  // in order of creation
  std::size_t modelCount() const;
  std::size_t functionCount() const;

 private:
  using FunctionMap = std::unordered_map<std::string, std::shared_ptr<FunctionEntry>, StringHash, std::equal_to<>>;
  // Both with mutex_ held: a model no longer referenced nor used by a function goes;
  // a function goes (and its model, when that was the last use).
  void dropModelIfUnused(const std::string& model_id, Released& released);
  void unloadFunction(FunctionMap::iterator it, Released& released);

  // With mutex_ held: RESOURCE_EXHAUSTED when `caller` holds its quota of models
  // (functions) and would take a new one; OK for another reference to one it holds.
  Status checkModelQuota(const std::string& caller, const ModelEntry* model) const;
  Status checkFunctionQuota(const std::string& caller, const FunctionEntry* function) const;

  ClientQuotas quotas_;
  mutable std::shared_mutex mutex_;
  std::unordered_map<std::string, std::shared_ptr<ModelEntry>, StringHash, std::equal_to<>> models_;
  FunctionMap functions_;
  std::uint64_t next_sequence_ = 0;
};

}  // namespace robodiff::server::detail
