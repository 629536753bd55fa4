// Client's batch jobs: SubmitJob, JobStatus, CancelJob and JobResult on the server the
// client is connected to (the jobs run in the server's worker processes; their files are
// written on its host).
#include "client_impl.hpp"

namespace robodiff::client {
namespace {

// The client's connection, or ClientError saying why there is none.
Connection& jobServerOf(Client::Impl& c) {
  if (!c.connection) throw ClientError(c.noServer());
  return *c.connection;
}

void throwJobFailure(const Status& s) {
  if (!s.ok()) throw ClientError(s);
}

}  // namespace

std::string Client::submitJob(const std::string& kind, const std::string& params_json) {
  rpc::SubmitJobRequest request{kind, params_json};
  rpc::SubmitJobReply reply;
  throwJobFailure(jobServerOf(*impl_).submitJob(request, reply, impl_->callOptions()));
  return reply.job_id;
}

std::vector<rpc::JobInfo> Client::jobs() {
  rpc::JobStatusReply reply;
  throwJobFailure(jobServerOf(*impl_).jobStatus(rpc::JobStatusRequest{}, reply, impl_->callOptions()));
  return reply.jobs;
}

rpc::JobInfo Client::jobStatus(const std::string& job_id) {
  if (job_id.empty())
    throw ClientError({StatusCode::InvalidArgument, "jobStatus: an empty job id (jobs() lists every job)"});
  rpc::JobStatusReply reply;
  throwJobFailure(jobServerOf(*impl_).jobStatus(rpc::JobStatusRequest{job_id}, reply, impl_->callOptions()));
  if (reply.jobs.empty()) throw ClientError({StatusCode::NotFound, "the server returned no job " + job_id});
  return reply.jobs.front();
}

rpc::JobState Client::cancelJob(const std::string& job_id) {
  rpc::CancelJobReply reply;
  throwJobFailure(jobServerOf(*impl_).cancelJob(rpc::CancelJobRequest{job_id}, reply, impl_->callOptions()));
  return reply.state;
}

rpc::JobResultReply Client::jobResult(const std::string& job_id) {
  rpc::JobResultReply reply;
  throwJobFailure(jobServerOf(*impl_).jobResult(rpc::JobResultRequest{job_id}, reply, impl_->callOptions()));
  return reply;
}

}  // namespace robodiff::client
