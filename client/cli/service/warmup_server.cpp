#include "service/warmup_server.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
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

std::string secondsText(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", s);
  return buf;
}

// One `robodiff warmup --server` run: registers every (robot, spec) pair with the
// service, then polls until each function is compiled or failed, or the time is up.
class ServerWarmup {
 public:
  ServerWarmup(const std::vector<workers::BuildTarget>& targets, const ServerWarmupOptions& options)
      : targets_(targets), wait_seconds_(options.timeout_seconds.value_or(900.0)), rows_(targets.size()) {
    ServiceArgs service;
    service.server = options.server;
    service.timeout_seconds = std::min(wait_seconds_, 30.0);
    c_ = connectService(service);
    rpc::HealthReply health;
    check(c_->health({}, health, c_.call()), "Health");
    compiles_ = health.workers_total > 0;
    std::vector<std::string> spec_paths;
    for (std::size_t i = 0; i < targets.size(); ++i) {
      rows_[i].status.robot = robotName(targets[i]);
      rows_[i].status.function = functionName(targets[i]);
      spec_paths.push_back(targets[i].spec_path);
    }
    progress_ = std::make_unique<WarmupProgress>(chooseProgressStyle(options.json), std::cout, spec_paths,
                                                 std::max(health.workers_total, 1u));
  }

  // True when every function compiled.
  bool run() {
    for (std::size_t i = 0; i < targets_.size(); ++i) registerTarget(i);
    pollUntilFinal();
    std::vector<BuildStatus> finals;
    for (const Row& r : rows_) finals.push_back(r.status);
    progress_->finish(finals);
    return std::none_of(rows_.begin(), rows_.end(), [](const Row& r) { return r.status.state == BuildState::Failed; });
  }

 private:
  double seconds() const { return std::chrono::duration<double>(Clock::now() - started_).count(); }

  void set(std::size_t i, BuildState state, const std::string& stage = "", const std::string& message = "") {
    Row& row = rows_[i];
    if (workers::isFinal(row.status.state)) return;
    row.status.state = state;
    row.status.stage = stage;
    row.status.message = message;
    row.status.seconds = seconds();
    progress_->update(i, row.status);
  }

  // The model of a target's robot, loaded once per (URDF, floating base): its id, or the
  // status LoadModel answered.
  const std::pair<std::string, Status>& model(const workers::BuildTarget& t) {
    auto it = models_.find({t.urdf_path, t.floating_base});
    if (it != models_.end()) return it->second;
    rpc::LoadModelRequest load;
    load.urdf = readTextFile(t.urdf_path, "--urdf");
    load.floating_base = t.floating_base;
    rpc::LoadModelReply reply;
    const Status s = c_->loadModel(load, reply, c_.call());
    if (s.code == StatusCode::Unavailable) throw ServiceError(s);
    return models_.emplace(std::make_pair(t.urdf_path, t.floating_base), std::make_pair(reply.model_id, s))
        .first->second;
  }

  // A model for the robot, then the function (GetFunction without waiting).
  void registerTarget(std::size_t i) {
    const workers::BuildTarget& t = targets_[i];
    set(i, BuildState::Queued);
    const auto& [model_id, loaded] = model(t);
    if (!loaded.ok()) return set(i, BuildState::Failed, "", "LoadModel: " + describe(loaded));
    rpc::GetFunctionRequest get;
    get.model_id = model_id;
    get.spec_json = readTextFile(t.spec_path, "--spec");
    get.wait = false;
    rpc::GetFunctionReply function;
    const Status s = c_->getFunction(get, function, c_.call());
    if (s.code == StatusCode::Unavailable) throw ServiceError(s);
    if (!s.ok()) return set(i, BuildState::Failed, "", "GetFunction: " + describe(s));
    rows_[i].function_id = function.function_id;
    rows_[i].status.key = function.function_id;
    // READY: compiled (from the cache, or built for another client) or not yet; the next
    // ListFunctions says which.
    if (function.state == rpc::FunctionState::Building) set(i, BuildState::Building, "trace");
  }

  bool pending() const {
    return std::any_of(rows_.begin(), rows_.end(), [](const Row& r) { return !workers::isFinal(r.status.state); });
  }

  void pollUntilFinal() {
    const auto deadline =
        started_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait_seconds_));
    while (pending()) {
      poll();
      if (!pending()) break;
      if (Clock::now() >= deadline) {
        for (std::size_t i = 0; i < rows_.size(); ++i)
          set(i, BuildState::Failed, "",
              "not compiled within " + secondsText(wait_seconds_) + " (--timeout); the server keeps building it");
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }

  // One look at every function (all pages of ListFunctions) and at the build queue.
  void poll() {
    std::vector<rpc::FunctionSummary> functions;
    const Status s = client::listAllFunctions(*c_.connection, {}, functions, c_.call());
    if (s.code == StatusCode::Unavailable) throw ServiceError(s);
    check(s, "ListFunctions");
    rpc::HealthReply now;
    const Status h = c_->health({}, now, c_.call());
    if (h.code == StatusCode::Unavailable) throw ServiceError(h);
    check(h, "Health");
    idle_polls_ = now.builds_queued + now.builds_running == 0 ? idle_polls_ + 1 : 0;
    std::map<std::string, const rpc::FunctionSummary*> by_id;
    for (const rpc::FunctionSummary& f : functions) by_id[f.function_id] = &f;
    for (std::size_t i = 0; i < rows_.size(); ++i) {
      if (workers::isFinal(rows_[i].status.state)) continue;
      const auto it = by_id.find(rows_[i].function_id);
      if (it == by_id.end())
        set(i, BuildState::Failed, "", "function " + rows_[i].function_id + " is no longer on the server (released?)");
      else
        observe(i, it->second->state, it->second->compiled, it->second->message);
    }
  }

  // A function's summary as its row's state. A function still not compiled after
  // idle_polls_ polls with no build queued or running will not be (the server counts a
  // build as queued before the function is READY; three polls let a finished build's
  // library be swapped in).
  void observe(std::size_t i, rpc::FunctionState state, bool compiled, const std::string& message) {
    Row& row = rows_[i];
    if (state == rpc::FunctionState::Failed) return set(i, BuildState::Failed, "", message);
    if (state == rpc::FunctionState::Building) return set(i, BuildState::Building, "trace");
    if (compiled) return set(i, row.saw_interpreted ? BuildState::Done : BuildState::Cached);
    row.saw_interpreted = true;
    if (!message.empty()) return set(i, BuildState::Failed, "", message);
    if (!compiles_ || idle_polls_ >= 3)
      return set(i, BuildState::Failed, "",
                 "the server is not compiling it (started with --interpreter-only?); its interpreter serves it");
    set(i, BuildState::Building, "compile");
  }

  const std::vector<workers::BuildTarget>& targets_;
  const double wait_seconds_;
  ServiceConnection c_;
  bool compiles_ = false;
  const Clock::time_point started_ = Clock::now();
  std::vector<Row> rows_;
  std::unique_ptr<WarmupProgress> progress_;
  std::map<std::pair<std::string, bool>, std::pair<std::string, Status>> models_;  // (urdf, floating) -> id, status
  int idle_polls_ = 0;
};

}  // namespace

void warmupOnServer(const std::vector<workers::BuildTarget>& targets, const ServerWarmupOptions& options) {
  if (!ServerWarmup(targets, options).run()) throw CLI::RuntimeError(1);
}

}  // namespace robodiff::cli
