// Client: loading models and functions, through the server when there is one, else from
// the local cache.
#include <fstream>
#include <sstream>

#include "client_impl.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/cache/prepared_build.hpp"

namespace robodiff::client {
namespace {

ModelInfo infoFrom(const rpc::LoadModelReply& reply) {
  ModelInfo info;
  info.id = reply.model_id;
  info.joint_names = reply.joint_names;
  info.frame_names = reply.frame_names;
  info.nq = static_cast<int>(reply.nq);
  info.nv = static_cast<int>(reply.nv);
  return info;
}

void throwIfFailed(const Status& s) {
  if (!s.ok()) throw ClientError(s);
}

}  // namespace

Client::Client(ClientOptions options) : impl_(connectClient(std::move(options))) {}
Client::~Client() = default;
Client::Client(Client&&) noexcept = default;
Client& Client::operator=(Client&&) noexcept = default;

Mode Client::mode() const { return impl_->mode(); }

ModelInfo Client::loadModel(const std::string& urdf_text, bool floating_base) {
  Impl& c = *impl_;
  Impl::ModelRecord record;
  record.urdf = urdf_text;
  record.floating_base = floating_base;
  bool loaded = false;
  if (c.connection && (!c.localCapable() || c.serverPresent())) {
    rpc::LoadModelRequest request;
    request.urdf = urdf_text;
    request.floating_base = floating_base;
    rpc::LoadModelReply reply;
    const Status s = c.connection->loadModel(request, reply, c.callOptions());
    if (s.ok()) {
      record.info = infoFrom(reply);
      loaded = true;
    } else if (s.code != StatusCode::Unavailable || !c.localCapable()) {
      throw ClientError(s);
    }
  } else if (!c.localCapable()) {
    throw ClientError(c.noServer());
  }
  if (!loaded) {  // Local without a server: the same id, computed here
    try {
      auto model = std::make_shared<const Model>(
          loadUrdfString(urdf_text, floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed));
      record.info.id = canonicalHash(*model);
      record.info.joint_names = model->jointNames();
      record.info.frame_names = model->frameNames();
      record.info.nq = model->nq;
      record.info.nv = model->nv;
      record.model = std::move(model);
    } catch (const std::exception& e) {
      throw ClientError({StatusCode::InvalidArgument, e.what()});
    }
  }
  std::lock_guard lock(c.registry_mutex);
  Impl::ModelRecord& kept = c.models[record.info.id];
  if (kept.info.id.empty()) kept = record;
  return record.info;
}

ModelInfo Client::loadModelFile(const std::filesystem::path& urdf_path, bool floating_base) {
  std::ifstream in(urdf_path, std::ios::binary);
  if (!in) throw ClientError({StatusCode::InvalidArgument, "cannot read the URDF file " + urdf_path.string()});
  std::stringstream text;
  text << in.rdbuf();
  return loadModel(text.str(), floating_base);
}

namespace {

// The function's layout from the server, which builds it first (GetFunction with wait).
// False without a server answer where the local cache may serve instead; throws where
// it may not.
bool layoutFromServer(Client::Impl& c, Function::Impl& f) {
  if (!c.connection || (c.localCapable() && !c.serverPresent())) {
    if (!c.localCapable()) throw ClientError(c.noServer());
    return false;
  }
  rpc::GetFunctionRequest request;
  request.model_id = f.model_id;
  request.spec_json = f.spec_json;
  request.wait = true;
  rpc::GetFunctionReply reply;
  const std::uint64_t generation = c.generation.load();
  Status s = c.connection->getFunction(request, reply, c.callOptions());
  if (s.code == StatusCode::NotFound) {  // a new server that does not know our model yet
    if (Status r = c.reregister(generation); r.ok()) s = c.connection->getFunction(request, reply, c.callOptions());
  }
  if (s.ok() && reply.state != rpc::FunctionState::Ready)
    s = {StatusCode::Internal, "GetFunction(wait) answered OK in state " + std::string(rpc::toString(reply.state))};
  if (s.ok()) {
    f.id = reply.function_id;
    f.layout = std::move(reply);
    return true;
  }
  if (s.code != StatusCode::Unavailable || !c.localCapable()) throw ClientError(s);
  return false;
}

// The keys the server builds under (cache::prepareBuild with function name "" and the
// default compiler), computed from the model parsed and hashed here. Returns why they
// could not be, or "".
std::string computeLocalKeys(Client::Impl& c, Function::Impl& f, const ModelInfo& model) {
  try {
    f.portable_keys = cache::portableKeysFor(model.id, f.spec, "");  // needs no compiler
    f.key = cache::prepareBuild(*c.localModel(model.id), model.id, f.spec, "", "").key;
  } catch (const ClientError&) {
    throw;
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// Without a server: the local cache must have the function's library.
void layoutFromCache(Client::Impl& c, Function::Impl& f, const ModelInfo& model, bool local, const std::string& problem) {
  if (!local)
    throw ClientError({StatusCode::FailedPrecondition,
                       "function " + f.spec_json.substr(0, 200) + " on model " + model.id + " is not in the local cache " +
                           c.cache->dir().string() + (problem.empty() ? "" : " (" + problem + ")") +
                           " and no robodiffd answers: run `robodiff warmup` for it, or start robodiffd"});
  f.layout = f.local.load()->layout();
  f.id = sha256Hex(model.id + "\n" + normalizedSpecJson(f.spec)).substr(0, 32);
  f.layout.function_id = f.id;
}

// With a server whose library is not in the cache (yet): the server compiles it, or our
// copy was refused. Evaluation goes through the server meanwhile (mode auto), and the
// calling thread looks at the cache again later.
void laterFromCache(Client::Impl& c, Function::Impl& f, std::string problem) {
  const std::optional<rpc::FunctionSummary> summary = c.summary(f.id);
  const bool server_compiled = summary && summary->compiled;
  bool local = false;
  if (server_compiled && problem.empty()) {  // compiled between our look and its answer?
    std::lock_guard lock(f.switch_mutex);
    local = f.tryLoadLocal(&problem);
  }
  if (local) return;
  if (c.requested == Mode::Local && (server_compiled || !problem.empty()))
    throw ClientError({StatusCode::FailedPrecondition,
                       "mode local: function " + f.id + ": the server compiled it but its library in " +
                           c.cache->dir().string() + " cannot be used here" +
                           (problem.empty() ? std::string(" (missing, or refused: a library whose SHA-256 "
                                                          "does not match the index is quarantined)")
                                            : " (" + problem + ")") +
                           "; use mode auto to evaluate through the server"});
  f.local_candidate = problem.empty();
  f.next_check_ns.store(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count() +
      100'000'000);
}

// The function's library from the local cache where this client can load one: now,
// or (with a server) once the cache has it.
void resolveLocally(Client::Impl& c, Function::Impl& f, const ModelInfo& model, bool from_server) {
  const std::string key_problem = computeLocalKeys(c, f, model);
  const bool have_keys = !f.key.empty() || !f.portable_keys.empty();
  std::string problem = key_problem;
  bool local = false;
  if (have_keys) {
    std::lock_guard lock(f.switch_mutex);
    local = f.tryLoadLocal(&problem);
  }
  if (!from_server) {
    layoutFromCache(c, f, model, local, problem);
  } else if (!local && have_keys) {
    laterFromCache(c, f, problem);
  } else if (c.requested == Mode::Local && !have_keys) {
    throw ClientError({StatusCode::FailedPrecondition,
                       "mode local: the cache key of function " + f.id + " cannot be computed here: " + key_problem});
  }
}

}  // namespace

Function Client::function(const ModelInfo& model, const std::string& spec_json) {
  Impl& c = *impl_;
  if (!c.knowsModel(model.id))
    throw ClientError({StatusCode::NotFound, "model " + model.id + " was not loaded by this client (loadModel first)"});
  auto f = std::make_shared<Function::Impl>();
  f->client = impl_;
  f->model_id = model.id;
  f->spec_json = spec_json;
  bool spec_parsed = false;
  std::string spec_problem;
  try {
    f->spec = parseFunctionSpec(spec_json, "spec_json");
    spec_parsed = true;
  } catch (const std::exception& e) {
    spec_problem = e.what();
  }
  const bool from_server = layoutFromServer(c, *f);
  if (!spec_parsed) {  // the server may know a spec this client cannot parse
    if (!from_server) throw ClientError({StatusCode::InvalidArgument, spec_problem});
  } else if (c.localCapable()) {
    resolveLocally(c, *f, model, from_server);
  }
  f->blocks = runtime::FunctionLayout::fromReply(f->layout);
  for (const rpc::OutputBlock& b : f->layout.outputs) {
    f->csr_rows.emplace_back(b.row_offsets.begin(), b.row_offsets.end());
    f->csr_cols.emplace_back(b.col_indices.begin(), b.col_indices.end());
  }
  {
    std::lock_guard lock(c.registry_mutex);
    c.functions[f->id] = Impl::FunctionRecord{model.id, spec_json};
  }
  return Function(std::move(f));
}

rpc::HealthReply Client::health() {
  Impl& c = *impl_;
  if (!c.connection) throw ClientError(c.noServer());
  rpc::HealthReply reply;
  throwIfFailed(c.connection->health({}, reply, c.callOptions()));
  return reply;
}

rpc::FleetStatusReply Client::fleetStatus() {
  Impl& c = *impl_;
  if (!c.connection) throw ClientError(c.noServer());
  const rpc::FleetStatusRequest request;
  rpc::FleetStatusReply reply;
  throwIfFailed(c.connection->call(UnaryCall{FleetStatusCall{&request, &reply}}, c.callOptions()));
  return reply;
}

Function Client::functionFile(const ModelInfo& model, const std::filesystem::path& spec_path) {
  std::ifstream in(spec_path);
  std::ostringstream text;
  if (!in || !(text << in.rdbuf()))
    throw ClientError({StatusCode::InvalidArgument, "cannot read the spec file " + spec_path.string()});
  return function(model, text.str());
}

std::vector<rpc::FunctionSummary> Client::functions() {
  Impl& c = *impl_;
  if (!c.connection) throw ClientError(c.noServer());
  std::vector<rpc::FunctionSummary> functions;
  throwIfFailed(listAllFunctions(*c.connection, {}, functions, c.callOptions()));
  return functions;
}

}  // namespace robodiff::client
