// robodiff._robodiff.JobInfo and the job calls on a Client (submit_job, jobs, job_status,
// cancel_job, job_result): the C++ Client's job API (client.hpp), the GIL released while
// the server answers. robodiff/jobs.py puts them on robodiff.Client.
#include <string>
#include <tuple>
#include <vector>

#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "robodiff/client/client.hpp"

namespace nb = nanobind;

namespace robodiff::python {
namespace {

using JobResultTuple = std::tuple<rpc::JobInfo, std::string, std::string>;  // info, result JSON, result dir

JobResultTuple jobResult(client::Client& c, const std::string& job_id) {
  rpc::JobResultReply reply = c.jobResult(job_id);
  return {std::move(reply.info), std::move(reply.result_json), std::move(reply.result_dir)};
}

std::string cancelJob(client::Client& c, const std::string& job_id) { return rpc::toString(c.cancelJob(job_id)); }

}  // namespace

void bindJobs(nb::module_& m) {
  nb::class_<rpc::JobInfo>(m, "JobInfo", "A batch job's state on the server (Client.job_status, Client.jobs).")
      .def_ro("job_id", &rpc::JobInfo::job_id, "The job's id (from Client.submit_job).")
      .def_ro("kind", &rpc::JobInfo::kind, "'trajectory', 'identify' or 'trajopt'.")
      .def_prop_ro(
          "state", [](const rpc::JobInfo& j) { return std::string(rpc::toString(j.state)); },
          "'QUEUED', 'RUNNING', 'SUCCEEDED', 'FAILED' or 'CANCELLED'.")
      .def_prop_ro(
          "done", [](const rpc::JobInfo& j) { return rpc::isFinal(j.state); },
          "True once the job succeeded, failed or was cancelled.")
      .def_ro("progress", &rpc::JobInfo::progress, "0 .. 1.")
      .def_ro("elapsed_seconds", &rpc::JobInfo::elapsed_seconds, "Since it started running (0 while queued).")
      .def_ro("eta_seconds", &rpc::JobInfo::eta_seconds, "Seconds remaining, from the progress; < 0: unknown.")
      .def_ro("messages", &rpc::JobInfo::messages, "What the job said: the latest few, oldest first.")
      .def_ro("error", &rpc::JobInfo::error, "FAILED / CANCELLED: why.")
      .def("__repr__", [](const rpc::JobInfo& j) {
        return "<robodiff.JobInfo " + j.job_id + " " + j.kind + " " + rpc::toString(j.state) + ">";
      });

  const auto release = nb::call_guard<nb::gil_scoped_release>();
  m.def(
      "submit_job",
      [](client::Client& c, const std::string& kind, const std::string& params) { return c.submitJob(kind, params); },
      nb::arg("client"), nb::arg("kind"), nb::arg("params_json"), release, "SubmitJob: the new job's id.");
  m.def(
      "jobs", [](client::Client& c) { return c.jobs(); }, nb::arg("client"), release,
      "JobStatus for every job the server knows.");
  m.def(
      "job_status", [](client::Client& c, const std::string& job_id) { return c.jobStatus(job_id); }, nb::arg("client"),
      nb::arg("job_id"), release, "JobStatus of one job.");
  m.def("cancel_job", &cancelJob, nb::arg("client"), nb::arg("job_id"), release,
        "CancelJob: the job's state after the cancel.");
  m.def("job_result", &jobResult, nb::arg("client"), nb::arg("job_id"), release,
        "JobResult: (JobInfo, result JSON text, result directory on the server's host).");
}

}  // namespace robodiff::python
