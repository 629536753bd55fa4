// What a Client has loaded, and registering it again on a server that does not know it
// (restarted): LoadModel + GetFunction(wait) for each, with the URDF text and spec kept
// here. Ids are content hashes, so the new server gives the same ids.
#include "client_impl.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::client {

std::shared_ptr<const Model> Client::Impl::localModel(const std::string& model_id) {
  std::string urdf;
  bool floating = false;
  {
    std::lock_guard lock(registry_mutex);
    const auto it = models.find(model_id);
    if (it == models.end())
      throw ClientError({StatusCode::NotFound, "model " + model_id + " was not loaded by this client"});
    if (it->second.model) return it->second.model;
    urdf = it->second.urdf;
    floating = it->second.floating_base;
  }
  std::shared_ptr<const Model> model;
  try {
    model = std::make_shared<const Model>(loadUrdfString(urdf, floating ? RootJoint::FreeFlyer : RootJoint::Fixed));
  } catch (const std::exception& e) {
    throw ClientError({StatusCode::InvalidArgument, e.what()});
  }
  std::lock_guard lock(registry_mutex);
  ModelRecord& record = models[model_id];
  if (!record.model) record.model = model;
  return record.model;
}

bool Client::Impl::knowsModel(const std::string& model_id) {
  std::lock_guard lock(registry_mutex);
  return models.count(model_id) != 0;
}

bool Client::Impl::knowsFunction(const std::string& function_id) {
  std::lock_guard lock(registry_mutex);
  return functions.count(function_id) != 0;
}

Status Client::Impl::reregister(std::uint64_t seen_generation) {
  if (!connection) return noServer();
  std::lock_guard once(reregister_mutex);
  if (generation.load() != seen_generation) return {};  // another thread did it meanwhile
  std::vector<ModelRecord> model_list;
  std::vector<FunctionRecord> function_list;
  {
    std::lock_guard lock(registry_mutex);
    for (const auto& [id, m] : models) model_list.push_back(m);
    for (const auto& [id, f] : functions) function_list.push_back(f);
  }
  for (const ModelRecord& m : model_list) {
    rpc::LoadModelRequest request;
    request.urdf = m.urdf;
    request.floating_base = m.floating_base;
    rpc::LoadModelReply reply;
    const Status s = connection->loadModel(request, reply, callOptions());
    if (!s.ok()) return s;
    if (reply.model_id != m.info.id)
      return {StatusCode::Internal, "registering again: the server gives model id " + reply.model_id +
                                        " for the URDF this client loaded as " + m.info.id};
  }
  for (const FunctionRecord& f : function_list) {
    rpc::GetFunctionRequest request;
    request.model_id = f.model_id;
    request.spec_json = f.spec_json;
    request.wait = true;
    rpc::GetFunctionReply reply;
    const Status s = connection->getFunction(request, reply, callOptions());
    if (!s.ok()) return s;
  }
  generation.fetch_add(1);
  return {};
}

std::optional<rpc::FunctionSummary> Client::Impl::summary(const std::string& function_id) {
  if (!connection) return std::nullopt;
  std::vector<rpc::FunctionSummary> functions;
  if (!listAllFunctions(*connection, {}, functions, callOptions()).ok()) return std::nullopt;
  for (rpc::FunctionSummary& f : functions)
    if (f.function_id == function_id) return std::move(f);
  return std::nullopt;
}

}  // namespace robodiff::client
