#include "registry.hpp"

#include <algorithm>
#include <mutex>

#include "robodiff/language/bounded_text.hpp"

namespace robodiff::server::detail {

namespace {

Status quotaExceeded(const std::string& caller, std::size_t held, std::size_t quota, const char* what,
                     const char* key, const char* release_with) {
  return {StatusCode::ResourceExhausted,
          "caller " + language::boundedText(caller) + " holds " + std::to_string(held) + " " + what +
              ", the most one client may hold (limits." + key + " = " + std::to_string(quota) + "); release " + what +
              " no longer used (Release with their " + release_with + ")"};
}

}  // namespace

Status Registry::checkModelQuota(const std::string& caller, const ModelEntry* model) const {
  if (model != nullptr && model->holders.holds(caller)) return {};
  std::size_t held = 0;
  for (const auto& [id, m] : models_) held += m->holders.holds(caller) ? 1 : 0;
  if (held < quotas_.max_models) return {};
  return quotaExceeded(caller, held, quotas_.max_models, "models", "max_models_per_client", "model_id");
}

Status Registry::checkFunctionQuota(const std::string& caller, const FunctionEntry* function) const {
  if (function != nullptr && function->holders.holds(caller)) return {};
  std::size_t held = 0;
  for (const auto& [id, f] : functions_) held += f->holders.holds(caller) ? 1 : 0;
  if (held < quotas_.max_functions) return {};
  return quotaExceeded(caller, held, quotas_.max_functions, "functions", "max_functions_per_client", "function_id");
}

Status Registry::addModel(std::shared_ptr<ModelEntry> candidate, std::size_t max_models, const std::string& caller,
                          Added& added) {
  std::unique_lock lock(mutex_);
  auto it = models_.find(candidate->id);
  if (Status s = checkModelQuota(caller, it == models_.end() ? nullptr : it->second.get()); !s.ok()) return s;
  if (it == models_.end()) {
    if (models_.size() >= max_models)
      return {StatusCode::ResourceExhausted, std::to_string(models_.size()) +
                                                 " models are loaded, the most this server allows (max_models); "
                                                 "release models no longer used (Release with their model_id)"};
    it = models_.emplace(candidate->id, std::move(candidate)).first;
    added.created = true;
  }
  added.model = it->second;
  added.references = it->second->holders.add(caller);
  return {};
}

Status Registry::addFunction(std::string_view model_id, const std::string& function_id, std::size_t max_functions,
                             const MakeFunction& make, const std::string& caller, Added& added) {
  std::unique_lock lock(mutex_);
  const auto model = models_.find(model_id);
  if (model == models_.end())
    return {StatusCode::NotFound, "unknown model id " + language::boundedText(model_id) +
                                      " (never loaded on this server, or released); call LoadModel first"};
  auto it = functions_.find(function_id);
  if (Status s = checkFunctionQuota(caller, it == functions_.end() ? nullptr : it->second.get()); !s.ok()) return s;
  if (it == functions_.end()) {
    if (functions_.size() >= max_functions)
      return {StatusCode::ResourceExhausted,
              std::to_string(functions_.size()) +
                  " functions are loaded, the most this server allows "
                  "(max_functions); release functions no longer used (Release with their function_id)"};
    it = functions_.emplace(function_id, make(model->second, next_sequence_++)).first;
    ++model->second->functions;
    added.created = true;
  }
  added.model = model->second;
  added.function = it->second;
  added.references = it->second->holders.add(caller);
  return {};
}

std::shared_ptr<FunctionEntry> Registry::findFunction(std::string_view function_id) const {
  std::shared_lock lock(mutex_);
  const auto it = functions_.find(function_id);
  return it == functions_.end() ? nullptr : it->second;
}

std::shared_ptr<ModelEntry> Registry::findModel(std::string_view model_id) const {
  std::shared_lock lock(mutex_);
  const auto it = models_.find(model_id);
  return it == models_.end() ? nullptr : it->second;
}

void Registry::dropModelIfUnused(const std::string& model_id, Released& released) {
  const auto m = models_.find(model_id);
  if (m != models_.end() && m->second->holders.total() == 0 && m->second->functions == 0) {
    released.model_unloaded = m->second;
    models_.erase(m);
  }
}

void Registry::unloadFunction(FunctionMap::iterator it, Released& released) {
  const std::shared_ptr<FunctionEntry> function = it->second;
  functions_.erase(it);
  function->markUnloaded();
  released.function_unloaded = function;
  if (const auto m = models_.find(function->model().id); m != models_.end()) --m->second->functions;
  dropModelIfUnused(function->model().id, released);
}

bool Registry::dropFailed(const std::shared_ptr<FunctionEntry>& function, Released& released) {
  std::unique_lock lock(mutex_);
  const auto it = functions_.find(function->id());
  if (it == functions_.end() || it->second != function) return false;
  released.was_function = true;
  unloadFunction(it, released);
  return true;
}

namespace {

// "function <id> is held by other callers ...": names no one (a caller learns nothing of others).
Status heldByOthers(std::string_view what, std::string_view id) {
  return {StatusCode::PermissionDenied, std::string(what) + " " + language::boundedText(id) +
                                            " belongs to another caller: it can only be released by a caller that "
                                            "loaded it (LoadModel / GetFunction) or by an operator"};
}

// Drops the caller's reference, or every reference for an operator that holds none.
Status dropReference(Holders& holders, const Caller& caller, std::string_view what, std::string_view id,
                     Registry::Released& released) {
  if (holders.drop(caller.name)) return {};
  if (!caller.operator_) return heldByOthers(what, id);
  holders.clear();
  released.forced = true;
  return {};
}

}  // namespace

Status Registry::release(std::string_view id, const Caller& caller, Released& released) {
  std::unique_lock lock(mutex_);
  if (const auto f = functions_.find(id); f != functions_.end()) {
    released.was_function = true;
    std::shared_ptr<FunctionEntry> function = f->second;
    if (Status s = dropReference(function->holders, caller, "function", id, released); !s.ok()) return s;
    released.references_left = function->holders.total();
    if (released.references_left == 0) unloadFunction(f, released);
    return {};
  }
  if (const auto m = models_.find(id); m != models_.end()) {
    if (m->second->holders.total() == 0)
      return {StatusCode::NotFound, "model " + language::boundedText(id) + " has no references left to release (" +
                                        std::to_string(m->second->functions) +
                                        " loaded functions keep it loaded until they are released)"};
    if (Status s = dropReference(m->second->holders, caller, "model", id, released); !s.ok()) return s;
    released.references_left = m->second->holders.total();
    dropModelIfUnused(m->second->id, released);
    return {};
  }
  return {StatusCode::NotFound, "unknown id " + language::boundedText(id) +
                                    ": no model or function with this id is loaded (never loaded, released, or a function that "
                                    "failed to build: those are unloaded at once)"};
}

std::vector<std::shared_ptr<FunctionEntry>> Registry::functions(std::optional<std::string_view> model_id,
                                                                 std::optional<std::string_view> holder) const {
  std::vector<std::shared_ptr<FunctionEntry>> out;
  {
    std::shared_lock lock(mutex_);
    for (const auto& [id, f] : functions_)
      if ((!model_id || f->model().id == *model_id) && (!holder || f->holders.holds(*holder))) out.push_back(f);
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a->sequence() < b->sequence(); });
  return out;
}

std::vector<Registry::ModelView> Registry::modelViews() const {
  std::vector<ModelView> out;
  {
    std::shared_lock lock(mutex_);
    for (const auto& [id, m] : models_) out.push_back({m, m->holders.total(), m->functions});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.model->id < b.model->id; });
  return out;
}

std::vector<Registry::FunctionView> Registry::functionViews() const {
  std::vector<FunctionView> out;
  {
    std::shared_lock lock(mutex_);
    for (const auto& [id, f] : functions_) out.push_back({f, f->holders.total()});
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.function->sequence() < b.function->sequence(); });
  return out;
}

std::size_t Registry::modelCount() const {
  std::shared_lock lock(mutex_);
  return models_.size();
}

std::size_t Registry::functionCount() const {
  std::shared_lock lock(mutex_);
  return functions_.size();
}

}  // namespace robodiff::server::detail
