#include "service/warmup_server.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <thread>

#include <CLI/CLI.hpp>

#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "service/service_connection.hpp"
#include "service/service_helpers.hpp"
#include "output/warmup_progress.hpp"

namespace robodiff::cli {
namespace {

using Clock = std::chrono::steady_clock;
using workers::BuildState;
using workers::BuildStatus;

struct Row {
  BuildStatus status;
  std::string function_id;  // empty: GetFunction did not give one (failed)
  bool saw_interpreted = false;  // READY and not compiled at some point: compiled here, not from the cache
};

std::string robotName(const workers::BuildTarget& t) {
  try {
    const Model model = loadUrdfFile(t.urdf_path, t.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed);
    if (!model.name.empty()) return model.name;
  } catch (const std::exception&) {
    // the server says what is wrong with it
  }
  return std::filesystem::path(t.urdf_path).stem().string();
}

std::string functionName(const workers::BuildTarget& t) {
  try {
    return loadFunctionSpec(t.spec_path).functionName();
  } catch (const std::exception&) {
    return std::filesystem::path(t.spec_path).stem().string();
  }
}

std::string describe(const Status& s) { return toString(s.code) + ": " + s.message; }

std::string secondsText(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", s);
  return buf;
}

}  // namespace

void warmupOnServer(const std::vector<workers::BuildTarget>& targets, const ServerWarmupOptions& options) {
  const double wait_seconds = options.timeout_seconds.value_or(900.0);
  ServiceArgs service;
  service.server = options.server;
  service.timeout_seconds = std::min(wait_seconds, 30.0);
  ServiceConnection c = connectService(service);

  rpc::HealthReply health;
  check(c->health({}, health, c.call()), "Health");
  const bool compiles = health.workers_total > 0;

  const auto started = Clock::now();
  const auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - started).count(); };
  std::vector<Row> rows(targets.size());
  std::vector<std::string> spec_paths;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    rows[i].status.robot = robotName(targets[i]);
    rows[i].status.function = functionName(targets[i]);
    spec_paths.push_back(targets[i].spec_path);
  }
  WarmupProgress progress(chooseProgressStyle(options.json), std::cout, spec_paths, std::max(health.workers_total, 1u));

  const auto set = [&](std::size_t i, BuildState state, const std::string& stage = "", const std::string& message = "") {
    Row& row = rows[i];
    if (workers::isFinal(row.status.state)) return;
    row.status.state = state;
    row.status.stage = stage;
    row.status.message = message;
    row.status.seconds = seconds();
    progress.update(i, row.status);
  };
  // A function's summary (or GetFunction's state) as a row's state.
  // Polls in a row in which the server had no build queued or running: a function that
  // is still not compiled then will not be (the server counts a build as queued before
  // the function is READY; three polls let a finished build's library be swapped in).
  int idle_polls = 0;
  const auto observe = [&](std::size_t i, rpc::FunctionState state, bool compiled, const std::string& message) {
    Row& row = rows[i];
    if (state == rpc::FunctionState::Failed) return set(i, BuildState::Failed, "", message);
    if (state == rpc::FunctionState::Building) return set(i, BuildState::Building, "trace");
    if (compiled) return set(i, row.saw_interpreted ? BuildState::Done : BuildState::Cached);
    row.saw_interpreted = true;
    if (!message.empty()) return set(i, BuildState::Failed, "", message);
    if (!compiles || idle_polls >= 3)
      return set(i, BuildState::Failed, "",
                 "the server is not compiling it (started with --interpreter-only?); its interpreter serves it");
    set(i, BuildState::Building, "compile");
  };

  // Register every pair: a model per robot, then its functions (without waiting).
  std::map<std::pair<std::string, bool>, std::pair<std::string, Status>> models;  // (urdf, floating) -> id, status
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const workers::BuildTarget& t = targets[i];
    set(i, BuildState::Queued);
    auto it = models.find({t.urdf_path, t.floating_base});
    if (it == models.end()) {
      rpc::LoadModelRequest load;
      load.urdf = readTextFile(t.urdf_path, "--urdf");
      load.floating_base = t.floating_base;
      rpc::LoadModelReply model;
      const Status s = c->loadModel(load, model, c.call());
      if (s.code == StatusCode::Unavailable) throw ServiceError(s);
      it = models.emplace(std::make_pair(t.urdf_path, t.floating_base), std::make_pair(model.model_id, s)).first;
    }
    if (!it->second.second.ok()) {
      set(i, BuildState::Failed, "", "LoadModel: " + describe(it->second.second));
      continue;
    }
    rpc::GetFunctionRequest get;
    get.model_id = it->second.first;
    get.spec_json = readTextFile(t.spec_path, "--spec");
    get.wait = false;
    rpc::GetFunctionReply function;
    const Status s = c->getFunction(get, function, c.call());
    if (s.code == StatusCode::Unavailable) throw ServiceError(s);
    if (!s.ok()) {
      set(i, BuildState::Failed, "", "GetFunction: " + describe(s));
      continue;
    }
    rows[i].function_id = function.function_id;
    rows[i].status.key = function.function_id;
    // READY: compiled (from the cache, or built for another client) or not yet; the next
    // ListFunctions says which.
    if (function.state == rpc::FunctionState::Building) set(i, BuildState::Building, "trace");
  }

  // Poll until every function is compiled or failed, or the time is up.
  const auto deadline = started + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait_seconds));
  const auto pending = [&] {
    return std::any_of(rows.begin(), rows.end(), [](const Row& r) { return !workers::isFinal(r.status.state); });
  };
  while (pending()) {
    rpc::ListFunctionsReply list;
    const Status s = c->listFunctions({}, list, c.call());
    if (s.code == StatusCode::Unavailable) throw ServiceError(s);
    check(s, "ListFunctions");
    rpc::HealthReply now;
    const Status h = c->health({}, now, c.call());
    if (h.code == StatusCode::Unavailable) throw ServiceError(h);
    check(h, "Health");
    idle_polls = now.builds_queued + now.builds_running == 0 ? idle_polls + 1 : 0;
    std::map<std::string, const rpc::FunctionSummary*> by_id;
    for (const rpc::FunctionSummary& f : list.functions) by_id[f.function_id] = &f;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (workers::isFinal(rows[i].status.state)) continue;
      const auto it = by_id.find(rows[i].function_id);
      if (it == by_id.end()) {
        set(i, BuildState::Failed, "", "function " + rows[i].function_id + " is no longer on the server (released?)");
        continue;
      }
      observe(i, it->second->state, it->second->compiled, it->second->message);
    }
    if (!pending()) break;
    if (Clock::now() >= deadline) {
      for (std::size_t i = 0; i < rows.size(); ++i)
        if (!workers::isFinal(rows[i].status.state))
          set(i, BuildState::Failed, "",
              "not compiled within " + secondsText(wait_seconds) + " (--timeout); the server keeps building it");
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }

  std::vector<BuildStatus> finals;
  for (const Row& r : rows) finals.push_back(r.status);
  progress.finish(finals);
  const bool failed = std::any_of(rows.begin(), rows.end(),
                                  [](const Row& r) { return r.status.state == BuildState::Failed; });
  if (failed) throw CLI::RuntimeError(1);
}

}  // namespace robodiff::cli
