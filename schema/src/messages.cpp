// Names of the message enums, and the per-knot sizes of a function's blocks.
#include "robodiff/schema/messages.hpp"

#include "robodiff.h"  // the idlc-generated C types: their enum values must equal ours

namespace robodiff::rpc {

static_assert(static_cast<std::uint32_t>(Method::LoadModel) == robodiff_wire_METHOD_LOAD_MODEL);
static_assert(static_cast<std::uint32_t>(Method::GetFunction) == robodiff_wire_METHOD_GET_FUNCTION);
static_assert(static_cast<std::uint32_t>(Method::Evaluate) == robodiff_wire_METHOD_EVALUATE);
static_assert(static_cast<std::uint32_t>(Method::EvaluateBatch) == robodiff_wire_METHOD_EVALUATE_BATCH);
static_assert(static_cast<std::uint32_t>(Method::ListFunctions) == robodiff_wire_METHOD_LIST_FUNCTIONS);
static_assert(static_cast<std::uint32_t>(Method::Health) == robodiff_wire_METHOD_HEALTH);
static_assert(static_cast<std::uint32_t>(Method::Release) == robodiff_wire_METHOD_RELEASE);
static_assert(static_cast<std::uint32_t>(Method::SubmitJob) == robodiff_wire_METHOD_SUBMIT_JOB);
static_assert(static_cast<std::uint32_t>(Method::JobStatus) == robodiff_wire_METHOD_JOB_STATUS);
static_assert(static_cast<std::uint32_t>(Method::CancelJob) == robodiff_wire_METHOD_CANCEL_JOB);
static_assert(static_cast<std::uint32_t>(Method::JobResult) == robodiff_wire_METHOD_JOB_RESULT);
static_assert(static_cast<std::uint32_t>(Method::QueryArtifact) == robodiff_wire_METHOD_QUERY_ARTIFACT);
static_assert(static_cast<std::uint32_t>(Method::FetchArtifactChunk) == robodiff_wire_METHOD_FETCH_ARTIFACT_CHUNK);
static_assert(static_cast<std::uint32_t>(Method::FleetStatus) == robodiff_wire_METHOD_FLEET_STATUS);
static_assert(static_cast<std::uint32_t>(JobState::Queued) == robodiff_wire_JOB_QUEUED);
static_assert(static_cast<std::uint32_t>(JobState::Cancelled) == robodiff_wire_JOB_CANCELLED);
static_assert(static_cast<std::uint32_t>(FunctionState::Ready) == robodiff_wire_FUNCTION_READY);
static_assert(static_cast<std::uint32_t>(FunctionState::Building) == robodiff_wire_FUNCTION_BUILDING);
static_assert(static_cast<std::uint32_t>(FunctionState::Failed) == robodiff_wire_FUNCTION_FAILED);
static_assert(static_cast<std::uint32_t>(OutputKind::Hessian) == robodiff_wire_OUTPUT_HESSIAN);
static_assert(static_cast<std::uint32_t>(OutputLayout::SparseCsr) == robodiff_wire_LAYOUT_SPARSE_CSR);
static_assert(static_cast<std::uint32_t>(ServingState::Draining) == robodiff_wire_SERVING_DRAINING);
static_assert(static_cast<std::uint32_t>(ArtifactState::Have) == robodiff_wire_ARTIFACT_HAVE);
static_assert(static_cast<std::uint32_t>(ArtifactState::Building) == robodiff_wire_ARTIFACT_BUILDING);
static_assert(static_cast<std::uint32_t>(ArtifactState::Lack) == robodiff_wire_ARTIFACT_LACK);
static_assert(static_cast<std::uint32_t>(ArtifactState::Failed) == robodiff_wire_ARTIFACT_FAILED);

const char* toString(Method method) {
  switch (method) {
    case Method::LoadModel: return "LoadModel";
    case Method::GetFunction: return "GetFunction";
    case Method::Evaluate: return "Evaluate";
    case Method::EvaluateBatch: return "EvaluateBatch";
    case Method::ListFunctions: return "ListFunctions";
    case Method::Health: return "Health";
    case Method::Release: return "Release";
    case Method::SubmitJob: return "SubmitJob";
    case Method::JobStatus: return "JobStatus";
    case Method::CancelJob: return "CancelJob";
    case Method::JobResult: return "JobResult";
    case Method::QueryArtifact: return "QueryArtifact";
    case Method::FetchArtifactChunk: return "FetchArtifactChunk";
    case Method::FleetStatus: return "FleetStatus";
  }
  return "UnknownMethod";
}

const char* toString(JobState state) {
  switch (state) {
    case JobState::Queued: return "QUEUED";
    case JobState::Running: return "RUNNING";
    case JobState::Succeeded: return "SUCCEEDED";
    case JobState::Failed: return "FAILED";
    case JobState::Cancelled: return "CANCELLED";
  }
  return "UNKNOWN";
}

const char* toString(FunctionState state) {
  switch (state) {
    case FunctionState::Ready: return "READY";
    case FunctionState::Building: return "BUILDING";
    case FunctionState::Failed: return "FAILED";
  }
  return "UNKNOWN_STATE";
}

const char* toString(ArtifactState state) {
  switch (state) {
    case ArtifactState::Have: return "HAVE";
    case ArtifactState::Building: return "BUILDING";
    case ArtifactState::Lack: return "LACK";
    case ArtifactState::Failed: return "FAILED";
  }
  return "UNKNOWN_STATE";
}

const char* toString(ServingState state) {
  switch (state) {
    case ServingState::Starting: return "STARTING";
    case ServingState::Serving: return "SERVING";
    case ServingState::Draining: return "DRAINING";
  }
  return "UNKNOWN_STATE";
}

std::uint32_t inputCount(const GetFunctionReply& function) {
  std::uint32_t n = 0;
  for (const InputBlock& b : function.inputs) n += b.size;
  return n;
}

std::uint32_t outputCount(const GetFunctionReply& function) {
  std::uint32_t n = 0;
  for (const OutputBlock& b : function.outputs) n += b.nnz;
  return n;
}

}  // namespace robodiff::rpc
