#include "registry.hpp"

#include <algorithm>
#include <mutex>

#include "robodiff/language/bounded_text.hpp"

namespace robodiff::server::detail {

Status Registry::addModel(std::shared_ptr<ModelEntry> candidate, std::size_t max_models, Added& added) {
  std::unique_lock lock(mutex_);
  auto it = models_.find(candidate->id);
  if (it == models_.end()) {
    if (models_.size() >= max_models)
      return {StatusCode::ResourceExhausted, std::to_string(models_.size()) +
                                                 " models are loaded, the most this server allows (max_models); "
                                                 "release models no longer used (Release with their model_id)"};
    it = models_.emplace(candidate->id, std::move(candidate)).first;
    added.created = true;
  }
  added.model = it->second;
  added.references = ++it->second->references;
  return {};
}

Status Registry::addFunction(std::string_view model_id, const std::string& function_id, std::size_t max_functions,
                             const MakeFunction& make, Added& added) {
  std::unique_lock lock(mutex_);
  const auto model = models_.find(model_id);
  if (model == models_.end())
    return {StatusCode::NotFound, "unknown model id " + language::boundedText(model_id) +
                                      " (never loaded on this server, or released); call LoadModel first"};
  auto it = functions_.find(function_id);
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
  added.references = ++it->second->references;
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
  if (m != models_.end() && m->second->references == 0 && m->second->functions == 0) {
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

Status Registry::release(std::string_view id, Released& released) {
  std::unique_lock lock(mutex_);
  if (const auto f = functions_.find(id); f != functions_.end()) {
    released.was_function = true;
    std::shared_ptr<FunctionEntry> function = f->second;
    released.references_left = --function->references;
    if (function->references == 0) unloadFunction(f, released);
    return {};
  }
  if (const auto m = models_.find(id); m != models_.end()) {
    if (m->second->references == 0)
      return {StatusCode::NotFound, "model " + language::boundedText(id) + " has no references left to release (" +
                                        std::to_string(m->second->functions) +
                                        " loaded functions keep it loaded until they are released)"};
    released.references_left = --m->second->references;
    dropModelIfUnused(m->second->id, released);
    return {};
  }
  return {StatusCode::NotFound, "unknown id " + language::boundedText(id) +
                                    ": no model or function with this id is loaded (never loaded, released, or a function that "
                                    "failed to build: those are unloaded at once)"};
}

std::vector<std::shared_ptr<FunctionEntry>> Registry::functions(std::optional<std::string_view> model_id) const {
  std::vector<std::shared_ptr<FunctionEntry>> out;
  {
    std::shared_lock lock(mutex_);
    for (const auto& [id, f] : functions_)
      if (!model_id || f->model().id == *model_id) out.push_back(f);
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a->sequence() < b->sequence(); });
  return out;
}

std::vector<Registry::ModelView> Registry::modelViews() const {
  std::vector<ModelView> out;
  {
    std::shared_lock lock(mutex_);
    for (const auto& [id, m] : models_) out.push_back({m, m->references, m->functions});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.model->id < b.model->id; });
  return out;
}

std::vector<Registry::FunctionView> Registry::functionViews() const {
  std::vector<FunctionView> out;
  {
    std::shared_lock lock(mutex_);
    for (const auto& [id, f] : functions_) out.push_back({f, f->references});
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
