// `robodiff job submit|status|cancel|result`: batch jobs on the running server
// (SubmitJob, JobStatus, CancelJob, JobResult). The job runs in the server's worker
// processes; its files are written on the server's host.
#include <chrono>
#include <cmath>
#include <iostream>
#include <thread>

#include <nlohmann/json.hpp>

#include "commands/commands.hpp"
#include "output/output_table.hpp"
#include "service/service_connection.hpp"
#include "service/service_helpers.hpp"

namespace robodiff::cli {
namespace {

using ojson = nlohmann::ordered_json;

struct JobArgs {
  ServiceArgs service;
  std::string kind, params_file, params_text, job_id;
  bool wait = false;
  bool json = false;
};

ojson toJson(const rpc::JobInfo& j) {
  return {{"job_id", j.job_id},
          {"kind", j.kind},
          {"state", rpc::toString(j.state)},
          {"progress", j.progress},
          {"elapsed_seconds", j.elapsed_seconds},
          {"eta_seconds", j.eta_seconds},
          {"messages", j.messages},
          {"error", j.error}};
}

std::string percent(double fraction) { return std::to_string(static_cast<int>(std::lround(fraction * 100))) + "%"; }

rpc::JobInfo statusOf(const ServiceConnection& c, const std::string& id) {
  rpc::JobStatusRequest request;
  request.job_id = id;
  rpc::JobStatusReply reply;
  check(c->jobStatus(request, reply, c.call()), "JobStatus");
  if (reply.jobs.empty()) throw ServiceError({StatusCode::NotFound, "the server returned no job " + id});
  return reply.jobs.front();
}

// Prints the result (JobResult) of a job that succeeded, or throws its failure.
void printResult(const ServiceConnection& c, const std::string& id, bool json) {
  rpc::JobResultRequest request;
  request.job_id = id;
  rpc::JobResultReply reply;
  check(c->jobResult(request, reply, c.call()), "JobResult");
  const nlohmann::json result = nlohmann::json::parse(reply.result_json.empty() ? "{}" : reply.result_json,
                                                      nullptr, false);
  if (json) {
    std::cout << ojson{{"job", toJson(reply.info)}, {"result_dir", reply.result_dir}, {"result", result}}.dump()
              << "\n";
    return;
  }
  std::cout << "job " << id << " " << rpc::toString(reply.info.state) << " in " << reply.info.elapsed_seconds
            << " s\nresult files: " << reply.result_dir << "\n"
            << result.dump(2) << "\n";
}

void submit(const JobArgs& args) {
  std::string params = args.params_text;
  if (!args.params_file.empty()) params = readTextFile(args.params_file, "--params");
  if (params.empty()) params = "{}";
  if (!nlohmann::json::parse(params, nullptr, false).is_object())
    throw UsageError("--params: not a JSON object: " + params.substr(0, 200));
  ServiceConnection c = connectService(args.service);
  rpc::SubmitJobRequest request;
  request.kind = args.kind;
  request.params_json = params;
  rpc::SubmitJobReply reply;
  check(c->submitJob(request, reply, c.call()), "SubmitJob");
  if (!args.wait) {
    if (args.json)
      std::cout << ojson{{"job_id", reply.job_id}}.dump() << "\n";
    else
      std::cout << reply.job_id << "\n";
    return;
  }
  // --wait: progress lines (stderr unless --json) until the job is final.
  std::string last;
  for (;;) {
    const rpc::JobInfo info = statusOf(c, reply.job_id);
    const std::string line = rpc::toString(info.state) + std::string(" ") + percent(info.progress) +
                             (info.messages.empty() ? "" : "  " + info.messages.back());
    if (!args.json && line != last) std::cerr << reply.job_id << ": " << line << "\n";
    last = line;
    if (rpc::isFinal(info.state)) {
      if (info.state == rpc::JobState::Succeeded) return printResult(c, reply.job_id, args.json);
      throw ServiceError({StatusCode::Aborted, "job " + reply.job_id + " " + rpc::toString(info.state) + ": " +
                                                   info.error});
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

void status(const JobArgs& args) {
  ServiceConnection c = connectService(args.service);
  rpc::JobStatusRequest request;
  request.job_id = args.job_id;
  rpc::JobStatusReply reply;
  check(c->jobStatus(request, reply, c.call()), "JobStatus");
  if (args.json) {
    ojson jobs = ojson::array();
    for (const rpc::JobInfo& j : reply.jobs) jobs.push_back(toJson(j));
    std::cout << ojson{{"jobs", jobs}}.dump() << "\n";
    return;
  }
  if (reply.jobs.empty()) {
    std::cout << "no jobs on the server\n";
    return;
  }
  Table table = Table::rows({"job", "kind", "state", "progress", "elapsed s", "eta s", "latest message / error"},
                            {false, false, false, true, true, true, false});
  for (const rpc::JobInfo& j : reply.jobs) {
    char elapsed[32], eta[32];
    std::snprintf(elapsed, sizeof elapsed, "%.1f", j.elapsed_seconds);
    std::snprintf(eta, sizeof eta, j.eta_seconds < 0 ? "-" : "%.1f", j.eta_seconds);
    std::string note = !j.error.empty() ? j.error : (j.messages.empty() ? "" : j.messages.back());
    if (note.size() > 100) note = note.substr(0, 97) + "...";
    table.addRow({j.job_id, j.kind, rpc::toString(j.state), percent(j.progress), elapsed, eta, note});
  }
  table.print(std::cout);
}

void cancel(const JobArgs& args) {
  ServiceConnection c = connectService(args.service);
  rpc::CancelJobRequest request;
  request.job_id = args.job_id;
  rpc::CancelJobReply reply;
  check(c->cancelJob(request, reply, c.call()), "CancelJob");
  if (args.json)
    std::cout << ojson{{"job_id", args.job_id}, {"state", rpc::toString(reply.state)}}.dump() << "\n";
  else
    std::cout << args.job_id << " " << rpc::toString(reply.state) << "\n";
}

void result(const JobArgs& args) {
  ServiceConnection c = connectService(args.service);
  printResult(c, args.job_id, args.json);
}

}  // namespace

void addJobCommand(CLI::App& app) {
  CLI::App* job = app.add_subcommand("job", "Batch jobs on the running server: submit, status, cancel, result");
  job->require_subcommand(1);

  auto s = std::make_shared<JobArgs>();
  CLI::App* sub = job->add_subcommand("submit", "Submit a job (SubmitJob); prints its id, or with --wait its result");
  sub->add_option("kind", s->kind, "trajectory | identify | trajopt")->required();
  auto* file = sub->add_option("--params", s->params_file,
                               "A JSON file with the job's parameters (paths are on the server's host, "
                               "under its jobs.data_dirs; schema/README.md lists them per kind)")
                   ->type_name("FILE");
  sub->add_option("--params-json", s->params_text, "The parameters as JSON text")->type_name("JSON")->excludes(file);
  sub->add_flag("--wait", s->wait, "Wait for the job, showing its progress, and print its result");
  sub->add_flag("--json", s->json, "JSON output");
  addServiceOptions(*sub, s->service);
  sub->footer(kServiceExitHelp);
  sub->callback([s] { submit(*s); });

  auto st = std::make_shared<JobArgs>();
  CLI::App* stat = job->add_subcommand("status", "A job's state, progress and messages, or every job (JobStatus)");
  stat->add_option("job_id", st->job_id, "The job (omit: all jobs the server knows)");
  stat->add_flag("--json", st->json, "JSON output");
  addServiceOptions(*stat, st->service);
  stat->footer(kServiceExitHelp);
  stat->callback([st] { status(*st); });

  auto c = std::make_shared<JobArgs>();
  CLI::App* can = job->add_subcommand("cancel", "Cancel a queued or running job (CancelJob); its files are removed");
  can->add_option("job_id", c->job_id, "The job")->required();
  can->add_flag("--json", c->json, "JSON output");
  addServiceOptions(*can, c->service);
  can->footer(kServiceExitHelp);
  can->callback([c] { cancel(*c); });

  auto r = std::make_shared<JobArgs>();
  CLI::App* res = job->add_subcommand("result", "A finished job's result summary and where its files are (JobResult)");
  res->add_option("job_id", r->job_id, "The job")->required();
  res->add_flag("--json", r->json, "JSON output");
  addServiceOptions(*res, r->service);
  res->footer(kServiceExitHelp);
  res->callback([r] { result(*r); });
}

}  // namespace robodiff::cli
