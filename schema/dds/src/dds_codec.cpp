// The DDS codec: rpc messages <-> idlc-generated C types. Every allocation is dds_alloc /
// dds_string_dup so that dds_sample_free(DDS_FREE_CONTENTS) releases it (see dds_codec.hpp).
#include "robodiff/schema/dds_codec.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace robodiff::dds_codec {

// ---- small pieces --------------------------------------------------------------------

char* dupString(std::string_view text) {
  char* out = static_cast<char*>(dds_alloc(text.size() + 1));
  if (!text.empty()) std::memcpy(out, text.data(), text.size());
  out[text.size()] = '\0';
  return out;
}

std::string toString(const char* text) { return text ? std::string(text) : std::string(); }

void allocDoubles(dds_sequence_double& sequence, std::size_t count) {
  sequence._buffer = count ? static_cast<double*>(dds_alloc(count * sizeof(double))) : nullptr;
  sequence._length = sequence._maximum = static_cast<uint32_t>(count);
  sequence._release = true;
}

void borrowDoubles(dds_sequence_double& sequence, std::span<const double> values) {
  sequence._buffer = const_cast<double*>(values.data());  // only read by dds_write
  sequence._length = sequence._maximum = static_cast<uint32_t>(values.size());
  sequence._release = false;
}

void detachDoubles(dds_sequence_double& sequence) {
  sequence._buffer = nullptr;
  sequence._length = sequence._maximum = 0;
  sequence._release = false;
}

StatusCode statusFromWire(robodiff_wire_StatusCode code) {
  return statusCodeFromValue(static_cast<std::uint32_t>(code)).value_or(StatusCode::Unknown);
}

std::optional<rpc::Method> methodFromWire(robodiff_wire_Method method) {
  const auto value = static_cast<std::uint32_t>(method);
  if (value >= rpc::kMethodCount) return std::nullopt;
  return static_cast<rpc::Method>(value);
}

namespace {

// Sequences of plain values (doubles, unsigned longs): one dds_alloc'd copy.
template <class Seq, class T>
void copyToWire(const std::vector<T>& in, Seq& out) {
  using Element = std::remove_pointer_t<decltype(out._buffer)>;
  static_assert(sizeof(Element) == sizeof(T));
  out._buffer = in.empty() ? nullptr : static_cast<Element*>(dds_alloc(in.size() * sizeof(T)));
  if (!in.empty()) std::memcpy(out._buffer, in.data(), in.size() * sizeof(T));
  out._length = out._maximum = static_cast<uint32_t>(in.size());
  out._release = true;
}

template <class Seq, class T>
void copyFromWire(const Seq& in, std::vector<T>& out) {
  out.assign(in._buffer, in._buffer ? in._buffer + in._length : in._buffer);
}

// Sequences of structs or strings: allocate the buffer zeroed, convert element by element.
template <class Seq, class T, class Convert>
void mapToWire(const std::vector<T>& in, Seq& out, Convert convert) {
  using Element = std::remove_pointer_t<decltype(out._buffer)>;
  out._buffer = in.empty() ? nullptr : static_cast<Element*>(dds_alloc(in.size() * sizeof(Element)));
  if (!in.empty()) std::memset(static_cast<void*>(out._buffer), 0, in.size() * sizeof(Element));
  out._length = out._maximum = static_cast<uint32_t>(in.size());
  out._release = true;
  for (std::size_t i = 0; i < in.size(); ++i) convert(in[i], out._buffer[i]);
}

template <class Seq, class T, class Convert>
void mapFromWire(const Seq& in, std::vector<T>& out, Convert convert) {
  out.clear();
  if (!in._buffer) return;
  out.resize(in._length);
  for (uint32_t i = 0; i < in._length; ++i) convert(in._buffer[i], out[i]);
}

void stringsToWire(const std::vector<std::string>& in, dds_sequence_string& out) {
  mapToWire(in, out, [](const std::string& s, char*& o) { o = dupString(s); });
}
void stringsFromWire(const dds_sequence_string& in, std::vector<std::string>& out) {
  mapFromWire(in, out, [](const char* s, std::string& o) { o = toString(s); });
}

template <class Out, class In>
Out castEnum(In value) {
  return static_cast<Out>(static_cast<std::uint32_t>(value));
}

}  // namespace

// ---- headers -------------------------------------------------------------------------

void toWire(const rpc::RequestHeader& h, robodiff_wire_RequestHeader& out) {
  out.schema_version.major = h.schema_version.major;
  out.schema_version.minor = h.schema_version.minor;
  out.client_id = dupString(h.client_id);
  out.correlation_id = h.correlation_id;
  out.deadline_budget_ns = h.deadline_budget_ns;
  out.server_instance_id = dupString(h.server_instance_id);
}

rpc::RequestHeader fromWire(const robodiff_wire_RequestHeader& h) {
  rpc::RequestHeader out;
  out.schema_version = {h.schema_version.major, h.schema_version.minor};
  out.client_id = toString(h.client_id);
  out.correlation_id = h.correlation_id;
  out.deadline_budget_ns = h.deadline_budget_ns;
  out.server_instance_id = toString(h.server_instance_id);
  return out;
}

void toWire(const rpc::ReplyHeader& h, robodiff_wire_ReplyHeader& out) {
  out.schema_version.major = h.schema_version.major;
  out.schema_version.minor = h.schema_version.minor;
  out.server_instance_id = dupString(h.server_instance_id);
  out.client_id = dupString(h.client_id);
  out.correlation_id = h.correlation_id;
  out.status.code = castEnum<robodiff_wire_StatusCode>(h.status.code);
  out.status.message = dupString(h.status.message);
}

rpc::ReplyHeader fromWire(const robodiff_wire_ReplyHeader& h) {
  rpc::ReplyHeader out;
  out.schema_version = {h.schema_version.major, h.schema_version.minor};
  out.server_instance_id = toString(h.server_instance_id);
  out.client_id = toString(h.client_id);
  out.correlation_id = h.correlation_id;
  out.status.code = statusFromWire(h.status.code);
  out.status.message = toString(h.status.message);
  return out;
}

// ---- requests ------------------------------------------------------------------------

void toWire(const rpc::LoadModelRequest& in, robodiff_wire_LoadModelRequest& out) {
  out.urdf = dupString(in.urdf);
  out.floating_base = in.floating_base;
  out.options_json = dupString(in.options_json);
}
void fromWire(const robodiff_wire_LoadModelRequest& in, rpc::LoadModelRequest& out) {
  out.urdf = toString(in.urdf);
  out.floating_base = in.floating_base;
  out.options_json = toString(in.options_json);
}

void toWire(const rpc::GetFunctionRequest& in, robodiff_wire_GetFunctionRequest& out) {
  out.model_id = dupString(in.model_id);
  out.spec_json = dupString(in.spec_json);
  out.wait = in.wait;
}
void fromWire(const robodiff_wire_GetFunctionRequest& in, rpc::GetFunctionRequest& out) {
  out.model_id = toString(in.model_id);
  out.spec_json = toString(in.spec_json);
  out.wait = in.wait;
}

void toWire(const rpc::EvaluateRequest& in, robodiff_wire_EvaluateRequest& out) {
  out.function_id = dupString(in.function_id);
  copyToWire(in.inputs, out.inputs);
}
void fromWire(const robodiff_wire_EvaluateRequest& in, rpc::EvaluateRequest& out) {
  out.function_id = toString(in.function_id);
  copyFromWire(in.inputs, out.inputs);
}

void toWire(const rpc::EvaluateBatchRequest& in, robodiff_wire_EvaluateBatchRequest& out) {
  out.function_id = dupString(in.function_id);
  out.knot_count = in.knot_count;
  copyToWire(in.inputs, out.inputs);
}
void fromWire(const robodiff_wire_EvaluateBatchRequest& in, rpc::EvaluateBatchRequest& out) {
  out.function_id = toString(in.function_id);
  out.knot_count = in.knot_count;
  copyFromWire(in.inputs, out.inputs);
}

void toWire(const rpc::ListFunctionsRequest& in, robodiff_wire_ListFunctionsRequest& out) {
  out.model_id = dupString(in.model_id);
  out.page_size = in.page_size;
  out.page_token = dupString(in.page_token);
}
void fromWire(const robodiff_wire_ListFunctionsRequest& in, rpc::ListFunctionsRequest& out) {
  out.model_id = toString(in.model_id);
  out.page_size = in.page_size;
  out.page_token = toString(in.page_token);
}

void toWire(const rpc::HealthRequest& in, robodiff_wire_HealthRequest& out) { out.verbose = in.verbose; }
void fromWire(const robodiff_wire_HealthRequest& in, rpc::HealthRequest& out) { out.verbose = in.verbose; }

void toWire(const rpc::ReleaseRequest& in, robodiff_wire_ReleaseRequest& out) { out.id = dupString(in.id); }
void fromWire(const robodiff_wire_ReleaseRequest& in, rpc::ReleaseRequest& out) { out.id = toString(in.id); }

// ---- replies -------------------------------------------------------------------------

void toWire(const rpc::LoadModelReply& in, robodiff_wire_LoadModelReply& out) {
  out.model_id = dupString(in.model_id);
  stringsToWire(in.joint_names, out.joint_names);
  stringsToWire(in.frame_names, out.frame_names);
  out.nq = in.nq;
  out.nv = in.nv;
}
void fromWire(const robodiff_wire_LoadModelReply& in, rpc::LoadModelReply& out) {
  out.model_id = toString(in.model_id);
  stringsFromWire(in.joint_names, out.joint_names);
  stringsFromWire(in.frame_names, out.frame_names);
  out.nq = in.nq;
  out.nv = in.nv;
}

void toWire(const rpc::GetFunctionReply& in, robodiff_wire_GetFunctionReply& out) {
  out.function_id = dupString(in.function_id);
  out.state = castEnum<robodiff_wire_FunctionState>(in.state);
  mapToWire(in.inputs, out.inputs, [](const rpc::InputBlock& b, robodiff_wire_InputBlock& o) {
    o.name = dupString(b.name);
    o.size = b.size;
  });
  mapToWire(in.outputs, out.outputs, [](const rpc::OutputBlock& b, robodiff_wire_OutputBlock& o) {
    o.name = dupString(b.name);
    o.kind = castEnum<robodiff_wire_OutputKind>(b.kind);
    o.rows = b.rows;
    o.cols = b.cols;
    o.layout = castEnum<robodiff_wire_OutputLayout>(b.layout);
    o.nnz = b.nnz;
    copyToWire(b.row_offsets, o.row_offsets);
    copyToWire(b.col_indices, o.col_indices);
  });
}
void fromWire(const robodiff_wire_GetFunctionReply& in, rpc::GetFunctionReply& out) {
  out.function_id = toString(in.function_id);
  out.state = castEnum<rpc::FunctionState>(in.state);
  mapFromWire(in.inputs, out.inputs, [](const robodiff_wire_InputBlock& b, rpc::InputBlock& o) {
    o.name = toString(b.name);
    o.size = b.size;
  });
  mapFromWire(in.outputs, out.outputs, [](const robodiff_wire_OutputBlock& b, rpc::OutputBlock& o) {
    o.name = toString(b.name);
    o.kind = castEnum<rpc::OutputKind>(b.kind);
    o.rows = b.rows;
    o.cols = b.cols;
    o.layout = castEnum<rpc::OutputLayout>(b.layout);
    o.nnz = b.nnz;
    copyFromWire(b.row_offsets, o.row_offsets);
    copyFromWire(b.col_indices, o.col_indices);
  });
}

void toWire(const rpc::EvaluateReply& in, robodiff_wire_EvaluateReply& out) { copyToWire(in.outputs, out.outputs); }
void fromWire(const robodiff_wire_EvaluateReply& in, rpc::EvaluateReply& out) { copyFromWire(in.outputs, out.outputs); }

void toWire(const rpc::EvaluateBatchReply& in, robodiff_wire_EvaluateBatchReply& out) {
  out.chunk_index = in.chunk_index;
  out.chunk_count = in.chunk_count;
  out.total_knots = in.total_knots;
  out.first_knot = in.first_knot;
  out.knot_count = in.knot_count;
  copyToWire(in.outputs, out.outputs);
}
void fromWire(const robodiff_wire_EvaluateBatchReply& in, rpc::EvaluateBatchReply& out) {
  out.chunk_index = in.chunk_index;
  out.chunk_count = in.chunk_count;
  out.total_knots = in.total_knots;
  out.first_knot = in.first_knot;
  out.knot_count = in.knot_count;
  copyFromWire(in.outputs, out.outputs);
}

void toWire(const rpc::ListFunctionsReply& in, robodiff_wire_ListFunctionsReply& out) {
  mapToWire(in.functions, out.functions, [](const rpc::FunctionSummary& f, robodiff_wire_FunctionSummary& o) {
    o.function_id = dupString(f.function_id);
    o.model_id = dupString(f.model_id);
    o.function_name = dupString(f.function_name);
    o.state = castEnum<robodiff_wire_FunctionState>(f.state);
    o.compiled = f.compiled;
    o.evaluations = f.evaluations;
    o.message = dupString(f.message);
  });
  out.next_page_token = dupString(in.next_page_token);
  out.total = in.total;
}
void fromWire(const robodiff_wire_ListFunctionsReply& in, rpc::ListFunctionsReply& out) {
  mapFromWire(in.functions, out.functions, [](const robodiff_wire_FunctionSummary& f, rpc::FunctionSummary& o) {
    o.function_id = toString(f.function_id);
    o.model_id = toString(f.model_id);
    o.function_name = toString(f.function_name);
    o.state = castEnum<rpc::FunctionState>(f.state);
    o.compiled = f.compiled;
    o.evaluations = f.evaluations;
    o.message = toString(f.message);
  });
  out.next_page_token = toString(in.next_page_token);
  out.total = in.total;
}

void toWire(const rpc::HealthReply& in, robodiff_wire_HealthReply& out) {
  out.state = castEnum<robodiff_wire_ServingState>(in.state);
  out.version = dupString(in.version);
  out.server_instance_id = dupString(in.server_instance_id);
  out.uptime_ns = in.uptime_ns;
  out.models_loaded = in.models_loaded;
  out.functions_loaded = in.functions_loaded;
  out.functions_compiled = in.functions_compiled;
  out.builds_queued = in.builds_queued;
  out.builds_running = in.builds_running;
  out.builds_failed = in.builds_failed;
  out.builds_done = in.builds_done;
  out.cache_hits = in.cache_hits;
  out.cache_misses = in.cache_misses;
  out.cache_bytes = in.cache_bytes;
  out.cache_entries = in.cache_entries;
  out.workers_total = in.workers_total;
  out.workers_busy = in.workers_busy;
  out.queue_depth = in.queue_depth;
  out.queue_capacity = in.queue_capacity;
  out.batch_threads = in.batch_threads;
  mapToWire(in.methods, out.methods, [](const rpc::MethodStats& m, robodiff_wire_MethodStats& o) {
    o.method = castEnum<robodiff_wire_Method>(m.method);
    o.requests = m.requests;
    o.errors = m.errors;
    o.p50_ns = m.p50_ns;
    o.p90_ns = m.p90_ns;
    o.p99_ns = m.p99_ns;
    o.max_ns = m.max_ns;
  });
  mapToWire(in.errors, out.errors, [](const rpc::StatusCount& c, robodiff_wire_StatusCount& o) {
    o.code = castEnum<robodiff_wire_StatusCode>(c.code);
    o.count = c.count;
  });
  mapToWire(in.transports, out.transports, [](const rpc::TransportCounts& t, robodiff_wire_TransportCounts& o) {
    o.transport = dupString(t.transport);
    o.requests = t.requests;
    o.errors = t.errors;
  });
}
void fromWire(const robodiff_wire_HealthReply& in, rpc::HealthReply& out) {
  out.state = castEnum<rpc::ServingState>(in.state);
  out.version = toString(in.version);
  out.server_instance_id = toString(in.server_instance_id);
  out.uptime_ns = in.uptime_ns;
  out.models_loaded = in.models_loaded;
  out.functions_loaded = in.functions_loaded;
  out.functions_compiled = in.functions_compiled;
  out.builds_queued = in.builds_queued;
  out.builds_running = in.builds_running;
  out.builds_failed = in.builds_failed;
  out.builds_done = in.builds_done;
  out.cache_hits = in.cache_hits;
  out.cache_misses = in.cache_misses;
  out.cache_bytes = in.cache_bytes;
  out.cache_entries = in.cache_entries;
  out.workers_total = in.workers_total;
  out.workers_busy = in.workers_busy;
  out.queue_depth = in.queue_depth;
  out.queue_capacity = in.queue_capacity;
  out.batch_threads = in.batch_threads;
  mapFromWire(in.methods, out.methods, [](const robodiff_wire_MethodStats& m, rpc::MethodStats& o) {
    o.method = castEnum<rpc::Method>(m.method);
    o.requests = m.requests;
    o.errors = m.errors;
    o.p50_ns = m.p50_ns;
    o.p90_ns = m.p90_ns;
    o.p99_ns = m.p99_ns;
    o.max_ns = m.max_ns;
  });
  mapFromWire(in.errors, out.errors, [](const robodiff_wire_StatusCount& c, rpc::StatusCount& o) {
    o.code = statusFromWire(c.code);
    o.count = c.count;
  });
  mapFromWire(in.transports, out.transports, [](const robodiff_wire_TransportCounts& t, rpc::TransportCounts& o) {
    o.transport = toString(t.transport);
    o.requests = t.requests;
    o.errors = t.errors;
  });
}

void toWire(const rpc::ReleaseReply& in, robodiff_wire_ReleaseReply& out) { out.references_left = in.references_left; }
void fromWire(const robodiff_wire_ReleaseReply& in, rpc::ReleaseReply& out) { out.references_left = in.references_left; }

// ---- jobs -------------------------------------------------------------------------------

namespace {

void jobInfoToWire(const rpc::JobInfo& in, robodiff_wire_JobInfo& out) {
  out.job_id = dupString(in.job_id);
  out.kind = dupString(in.kind);
  out.state = castEnum<robodiff_wire_JobState>(in.state);
  out.progress = in.progress;
  out.elapsed_seconds = in.elapsed_seconds;
  out.eta_seconds = in.eta_seconds;
  stringsToWire(in.messages, out.messages);
  out.error = dupString(in.error);
}

void jobInfoFromWire(const robodiff_wire_JobInfo& in, rpc::JobInfo& out) {
  out.job_id = toString(in.job_id);
  out.kind = toString(in.kind);
  out.state = castEnum<rpc::JobState>(in.state);
  out.progress = in.progress;
  out.elapsed_seconds = in.elapsed_seconds;
  out.eta_seconds = in.eta_seconds;
  stringsFromWire(in.messages, out.messages);
  out.error = toString(in.error);
}

}  // namespace

void toWire(const rpc::SubmitJobRequest& in, robodiff_wire_SubmitJobRequest& out) {
  out.kind = dupString(in.kind);
  out.params_json = dupString(in.params_json);
}
void fromWire(const robodiff_wire_SubmitJobRequest& in, rpc::SubmitJobRequest& out) {
  out.kind = toString(in.kind);
  out.params_json = toString(in.params_json);
}
void toWire(const rpc::JobStatusRequest& in, robodiff_wire_JobStatusRequest& out) { out.job_id = dupString(in.job_id); }
void fromWire(const robodiff_wire_JobStatusRequest& in, rpc::JobStatusRequest& out) { out.job_id = toString(in.job_id); }
void toWire(const rpc::CancelJobRequest& in, robodiff_wire_CancelJobRequest& out) { out.job_id = dupString(in.job_id); }
void fromWire(const robodiff_wire_CancelJobRequest& in, rpc::CancelJobRequest& out) { out.job_id = toString(in.job_id); }
void toWire(const rpc::JobResultRequest& in, robodiff_wire_JobResultRequest& out) { out.job_id = dupString(in.job_id); }
void fromWire(const robodiff_wire_JobResultRequest& in, rpc::JobResultRequest& out) { out.job_id = toString(in.job_id); }

void toWire(const rpc::SubmitJobReply& in, robodiff_wire_SubmitJobReply& out) { out.job_id = dupString(in.job_id); }
void fromWire(const robodiff_wire_SubmitJobReply& in, rpc::SubmitJobReply& out) { out.job_id = toString(in.job_id); }
void toWire(const rpc::JobStatusReply& in, robodiff_wire_JobStatusReply& out) {
  mapToWire(in.jobs, out.jobs, jobInfoToWire);
}
void fromWire(const robodiff_wire_JobStatusReply& in, rpc::JobStatusReply& out) {
  mapFromWire(in.jobs, out.jobs, jobInfoFromWire);
}
void toWire(const rpc::CancelJobReply& in, robodiff_wire_CancelJobReply& out) {
  out.state = castEnum<robodiff_wire_JobState>(in.state);
}
void fromWire(const robodiff_wire_CancelJobReply& in, rpc::CancelJobReply& out) {
  out.state = castEnum<rpc::JobState>(in.state);
}
void toWire(const rpc::JobResultReply& in, robodiff_wire_JobResultReply& out) {
  jobInfoToWire(in.info, out.info);
  out.result_json = dupString(in.result_json);
  out.result_dir = dupString(in.result_dir);
}
void fromWire(const robodiff_wire_JobResultReply& in, rpc::JobResultReply& out) {
  jobInfoFromWire(in.info, out.info);
  out.result_json = toString(in.result_json);
  out.result_dir = toString(in.result_dir);
}

// ---- envelopes -------------------------------------------------------------------------

namespace {

// Body variant -> union: the variant index is the discriminator (same order as Method).
template <class Body, class Union>
void bodyToWire(const Body& body, Union& out) {
  out._d = static_cast<robodiff_wire_Method>(body.index());
  std::visit(
      [&](const auto& message) {
        using M = std::decay_t<decltype(message)>;
        if constexpr (std::is_same_v<M, rpc::LoadModelRequest> || std::is_same_v<M, rpc::LoadModelReply>)
          toWire(message, out._u.load_model);
        else if constexpr (std::is_same_v<M, rpc::GetFunctionRequest> || std::is_same_v<M, rpc::GetFunctionReply>)
          toWire(message, out._u.get_function);
        else if constexpr (std::is_same_v<M, rpc::EvaluateRequest> || std::is_same_v<M, rpc::EvaluateReply>)
          toWire(message, out._u.evaluate);
        else if constexpr (std::is_same_v<M, rpc::EvaluateBatchRequest> || std::is_same_v<M, rpc::EvaluateBatchReply>)
          toWire(message, out._u.evaluate_batch);
        else if constexpr (std::is_same_v<M, rpc::ListFunctionsRequest> ||
                           std::is_same_v<M, rpc::ListFunctionsReply>)
          toWire(message, out._u.list_functions);
        else if constexpr (std::is_same_v<M, rpc::HealthRequest> || std::is_same_v<M, rpc::HealthReply>)
          toWire(message, out._u.health);
        else if constexpr (std::is_same_v<M, rpc::ReleaseRequest> || std::is_same_v<M, rpc::ReleaseReply>)
          toWire(message, out._u.release);
        else if constexpr (std::is_same_v<M, rpc::SubmitJobRequest> || std::is_same_v<M, rpc::SubmitJobReply>)
          toWire(message, out._u.submit_job);
        else if constexpr (std::is_same_v<M, rpc::JobStatusRequest> || std::is_same_v<M, rpc::JobStatusReply>)
          toWire(message, out._u.job_status);
        else if constexpr (std::is_same_v<M, rpc::CancelJobRequest> || std::is_same_v<M, rpc::CancelJobReply>)
          toWire(message, out._u.cancel_job);
        else
          toWire(message, out._u.job_result);
      },
      body);
}

template <class Body, class Union>
Status bodyFromWire(const Union& in, Body& out) {
  const auto method = methodFromWire(in._d);
  if (!method)
    return {StatusCode::InvalidArgument,
            "unknown method " + std::to_string(static_cast<std::uint32_t>(in._d)) +
                " in the body's discriminator (this server knows 0.." + std::to_string(rpc::kMethodCount - 1) +
                "; is the client newer?)"};
  switch (*method) {
    case rpc::Method::LoadModel: fromWire(in._u.load_model, out.template emplace<0>()); break;
    case rpc::Method::GetFunction: fromWire(in._u.get_function, out.template emplace<1>()); break;
    case rpc::Method::Evaluate: fromWire(in._u.evaluate, out.template emplace<2>()); break;
    case rpc::Method::EvaluateBatch: fromWire(in._u.evaluate_batch, out.template emplace<3>()); break;
    case rpc::Method::ListFunctions: fromWire(in._u.list_functions, out.template emplace<4>()); break;
    case rpc::Method::Health: fromWire(in._u.health, out.template emplace<5>()); break;
    case rpc::Method::Release: fromWire(in._u.release, out.template emplace<6>()); break;
    case rpc::Method::SubmitJob: fromWire(in._u.submit_job, out.template emplace<7>()); break;
    case rpc::Method::JobStatus: fromWire(in._u.job_status, out.template emplace<8>()); break;
    case rpc::Method::CancelJob: fromWire(in._u.cancel_job, out.template emplace<9>()); break;
    case rpc::Method::JobResult: fromWire(in._u.job_result, out.template emplace<10>()); break;
  }
  return {};
}

}  // namespace

void toWire(const RequestBody& body, robodiff_wire_RequestBody& out) { bodyToWire(body, out); }
void toWire(const ReplyBody& body, robodiff_wire_ReplyBody& out) { bodyToWire(body, out); }
Status fromWire(const robodiff_wire_RequestBody& body, RequestBody& out) { return bodyFromWire(body, out); }
Status fromWire(const robodiff_wire_ReplyBody& body, ReplyBody& out) { return bodyFromWire(body, out); }

ReplyBody emptyReplyBody(rpc::Method method) {
  switch (method) {
    case rpc::Method::LoadModel: return rpc::LoadModelReply{};
    case rpc::Method::GetFunction: return rpc::GetFunctionReply{};
    case rpc::Method::Evaluate: return rpc::EvaluateReply{};
    case rpc::Method::EvaluateBatch: return rpc::EvaluateBatchReply{};
    case rpc::Method::ListFunctions: return rpc::ListFunctionsReply{};
    case rpc::Method::Health: return rpc::HealthReply{};
    case rpc::Method::Release: return rpc::ReleaseReply{};
    case rpc::Method::SubmitJob: return rpc::SubmitJobReply{};
    case rpc::Method::JobStatus: return rpc::JobStatusReply{};
    case rpc::Method::CancelJob: return rpc::CancelJobReply{};
    case rpc::Method::JobResult: return rpc::JobResultReply{};
  }
  return rpc::HealthReply{};
}

}  // namespace robodiff::dds_codec
