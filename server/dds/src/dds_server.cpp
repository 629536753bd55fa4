// DdsServer: the receive thread, admission, inline Evaluate and the posted methods.
#include "robodiff/server/dds_server.hpp"

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "caller_identity.hpp"
#include "reply_channels.hpp"
#include "reply_writer.hpp"
#include "robodiff/schema/dds_codec.hpp"
#include "robodiff/server/error_budget.hpp"
#include "robodiff/server/fair_scheduler.hpp"

namespace robodiff::server {

using dds_codec::WireRequest;
using dds_detail::ReplyWriter;
using dds_detail::RequestInfo;

struct DdsServer::Core : std::enable_shared_from_this<DdsServer::Core> {
  Core(ServiceApi& s, DdsServerOptions o, Logger& l)
      : service(s), options(std::move(o)), log(l), replies(s, l, options.max_sample_bytes), scheduler(options.fair),
        refused(options.error_replies_per_second), malformed(options.error_replies_per_second),
        unanswerable(options.error_replies_per_second) {}

  ServiceApi& service;
  DdsServerOptions options;
  Logger& log;
  ReplyWriter replies;

  std::unique_ptr<dds_codec::DdsEndpoints> endpoints;
  std::unique_ptr<dds_detail::DdsCallers> callers;  // who sent a request (caller_identity.hpp)
  std::unique_ptr<dds_detail::ReplyChannels> channels;  // where to answer it (reply_channels.hpp)
  dds_entity_t guard = 0;  // wakes the receive thread on stop()
  std::thread receiver;
  std::atomic<bool> stopping{false};
  std::atomic<bool> accepting{true};

  std::atomic<std::int64_t> waiting{0};  // posted, not yet started
  std::atomic<std::size_t> in_flight{0};
  std::mutex idle_mutex;
  std::condition_variable idle_cv;

  // Fair sharing (fair_scheduler.hpp): a lane per writer (info.publication), served in
  // turn; over-quota and unknown-method requests answered within an error budget.
  struct Queued {
    std::shared_ptr<WireRequest> sample;
    RequestInfo info;
  };
  FairScheduler<Queued> scheduler;
  ErrorBudget refused, malformed, unanswerable;

  void receiveLoop();
  void refreshChannels();
  bool drain(dds_entity_t reader);
  void serve(Queued queued);
  void postFair(Queued queued);
  void enqueue(std::shared_ptr<WireRequest> sample, RequestInfo info);
  void handle(std::shared_ptr<WireRequest> sample, Clock::time_point received, dds_instance_handle_t publication);
  void evaluateInline(const RequestInfo& info, const robodiff_wire_EvaluateRequest& request);
  void post(std::shared_ptr<WireRequest> sample, RequestInfo info);
  void runPosted(const robodiff_wire_Request& sample, const RequestInfo& info);
  void evaluateBatch(const RequestInfo& info, const robodiff_wire_EvaluateBatchRequest& request);
  void done() {
    if (in_flight.fetch_sub(1) == 1) {
      std::lock_guard lock(idle_mutex);
      idle_cv.notify_all();
    }
  }
};

namespace {

// Marks one request done (in-flight count) when the last copy of a posted task goes away,
// whether the task ran or the service dropped it.
// Also hands the writer's next deferred request to the service (FairScheduler).
struct InFlight {
  InFlight(std::shared_ptr<DdsServer::Core> c, const RequestInfo& info)
      : core(std::move(c)), client(info.publication), quota(info.quota) {}
  InFlight(const InFlight&) = delete;
  InFlight& operator=(const InFlight&) = delete;
  ~InFlight() {
    auto next = core->scheduler.finishPosted(client, quota->slot);
    core->done();
    if (next) core->post(std::move(next->sample), std::move(next->info));
  }
  std::shared_ptr<DdsServer::Core> core;
  std::uint64_t client;
  std::shared_ptr<dds_detail::QuotaRelease> quota;  // a posted request was queued: always set
};

}  // namespace

DdsServer::DdsServer(ServiceApi& service, DdsServerOptions options, Logger& log)
    : core_(std::make_shared<Core>(service, std::move(options), log)) {}

DdsServer::~DdsServer() { stop(); }

void DdsServer::start() {
  Core& c = *core_;
  if (c.endpoints) throw std::logic_error("DdsServer::start() called twice");
  c.endpoints = std::make_unique<dds_codec::DdsEndpoints>(c.options.domain_id, c.options.service_name,
                                                          dds_codec::DdsEndpoints::Side::Server,
                                                          c.options.write_blocking, c.options.lease,
                                                          c.options.security);
  c.guard = dds_create_guardcondition(c.endpoints->participant());
  if (c.guard < 0) {
    c.endpoints.reset();
    throw std::runtime_error(dds_codec::ddsError("dds_create_guardcondition", c.guard));
  }
  c.callers = std::make_unique<dds_detail::DdsCallers>(c.endpoints->reader(), c.options.security.enabled());
  c.channels = std::make_unique<dds_detail::ReplyChannels>(
      c.endpoints->reader(),
      [endpoints = c.endpoints.get()](const std::string& partition) { return endpoints->createReplyWriter(partition); },
      dds_detail::kMaxKnownPublications);
  // The receive thread hears of request publications (dis)appearing: reply channels follow.
  dds_set_status_mask(c.endpoints->reader(), DDS_SUBSCRIPTION_MATCHED_STATUS);
  c.receiver = std::thread([core = core_] { core->receiveLoop(); });
  c.log.info("dds_server_started", {{"domain", c.endpoints->domainId()},
                                    {"request_topic", c.endpoints->readerTopic()},
                                    {"reply_topic", c.endpoints->writerTopic()},
                                    {"server_instance_id", c.service.instanceId()},
                                    {"security", c.options.security.enabled()
                                                     ? "DDS Security, " + c.options.security.describe()
                                                     : std::string("open (unauthenticated)")}});
}

void DdsServer::stopAccepting() { core_->accepting = false; }

bool DdsServer::waitIdle(std::chrono::milliseconds timeout) {
  std::unique_lock lock(core_->idle_mutex);
  return core_->idle_cv.wait_for(lock, timeout, [&] { return core_->in_flight.load() == 0; });
}

void DdsServer::stop() {
  Core& c = *core_;
  if (c.stopping.exchange(true) || !c.endpoints) return;
  dds_set_guardcondition(c.guard, true);
  if (c.receiver.joinable()) c.receiver.join();
  c.replies.close();  // posted tasks still running drop their replies
  if (c.channels) c.channels->close();
  const auto domain = c.endpoints->domainId();
  c.endpoints.reset();     // deletes the participant: clients see this server go away
  c.log.info("dds_server_stopped", {{"domain", domain}, {"in_flight", c.in_flight.load()}});
}

Status DdsServer::ready() const {
  const Core& c = *core_;
  if (!c.endpoints) return {StatusCode::Unavailable, "DDS server not started"};
  if (c.stopping) return {StatusCode::Unavailable, "DDS server stopping"};
  dds_domainid_t domain = 0;
  if (const dds_return_t rc = dds_get_domainid(c.endpoints->participant(), &domain); rc != DDS_RETCODE_OK)
    return {StatusCode::Unavailable, "DDS participant: " + dds_codec::ddsError("dds_get_domainid", rc)};
  std::uint32_t changes = 0;
  if (const dds_return_t rc = dds_get_status_changes(c.endpoints->reader(), &changes); rc != DDS_RETCODE_OK)
    return {StatusCode::Unavailable, "DDS request reader: " + dds_codec::ddsError("dds_get_status_changes", rc)};
  return {};
}

std::size_t DdsServer::inFlight() const { return core_->in_flight.load(); }
std::uint32_t DdsServer::domainId() const { return core_->endpoints ? core_->endpoints->domainId() : 0; }
std::string DdsServer::requestTopic() const { return dds_codec::requestTopicName(core_->options.service_name); }
std::string DdsServer::replyTopic() const { return dds_codec::replyTopicName(core_->options.service_name); }

// ---- the receive thread ------------------------------------------------------------------

void DdsServer::Core::receiveLoop() {
  const dds_entity_t participant = endpoints->participant(), reader = endpoints->reader();
  const dds_entity_t waitset = dds_create_waitset(participant);
  const dds_entity_t readable = dds_create_readcondition(reader, DDS_ANY_STATE);
  dds_waitset_attach(waitset, readable, 0);
  dds_waitset_attach(waitset, guard, 0);
  dds_waitset_attach(waitset, reader, 0);  // subscription matched: a client came or went
  refreshChannels();
  while (!stopping) {
    dds_waitset_wait(waitset, nullptr, 0, DDS_INFINITY);
    uint32_t matched = 0;
    if (dds_take_status(reader, &matched, DDS_SUBSCRIPTION_MATCHED_STATUS) == DDS_RETCODE_OK && matched != 0)
      refreshChannels();
    // Take what the reader holds into the lanes, serve the next writer's request, repeat.
    while (!stopping) {
      drain(reader);
      auto next = scheduler.next();
      if (!next) break;
      serve(std::move(next->item));
    }
  }
  dds_delete(readable);
  dds_delete(waitset);
}

// Reply channels follow the matched request publications; a caller partition refused one is
// logged once; the dropped ones are deleted on a request thread (a writer's deletion may
// wait for acknowledgements), here if the service's queue is full.
void DdsServer::Core::refreshChannels() {
  auto refreshed = channels->refresh();
  for (const std::string& problem : refreshed.problems) log.warn("dds_reply_writer_refused", {{"error", problem}});
  if (!refreshed.dropped.empty()) service.post([dropped = std::move(refreshed.dropped)] {});
}

// Takes up to kDrainBatch samples (checked, refused or queued in their writer's lane).
bool DdsServer::Core::drain(dds_entity_t reader) {
  constexpr int kDrainBatch = 256;
  int taken = 0;
  for (; taken < kDrainBatch && !stopping; ++taken) {
    // Taken into memory we own (not a loan), so that a posted task can keep it.
    auto sample = std::make_shared<WireRequest>();
    void* buffer[1] = {&sample->get()};
    dds_sample_info_t info;
    if (dds_take(reader, buffer, &info, 1, 1) <= 0) break;
    if (!info.valid_data) continue;  // a writer went away: nothing to answer
    handle(std::move(sample), Clock::now(), info.publication_handle);
  }
  return taken > 0;
}

// Into the writer's lane; a writer with limits.max_queued_requests_per_client pending is
// refused RESOURCE_EXHAUSTED (within its error budget).
void DdsServer::Core::enqueue(std::shared_ptr<WireRequest> sample, RequestInfo info) {
  const std::uint64_t client = info.publication;
  info.quota = std::make_shared<dds_detail::QuotaRelease>();
  info.quota->release = [this, client](QuotaSlot& slot) { scheduler.answered(client, slot); };
  if (scheduler.push(client, Queued{sample, info})) {
    info.quota->slot.admit();  // the queued copy shares it; served on this thread, later
    return;
  }
  const auto d = refused.note(client, info.received);
  const std::uint32_t quota = scheduler.limits().max_queued;
  if (d.log)
    log.warn("dds_client_over_queue_quota", {{"client_id", info.header.client_id}, {"count", d.count},
                                             {"dropped_unanswered", d.dropped},
                                             {"max_queued_requests_per_client", quota}});
  if (d.reply)
    replies.sendError(info, {StatusCode::ResourceExhausted,
                             "this client has " + std::to_string(quota) +
                                 " requests pending, the most one client may have "
                                 "(limits.max_queued_requests_per_client = " +
                                 std::to_string(quota) + "); wait for replies before sending more"});
  done();
}

// The next request in turn: Evaluate on this thread, the others on the request threads.
void DdsServer::Core::serve(Queued queued) {
  const std::uint64_t client = queued.info.publication;
  if (queued.info.method != rpc::Method::Evaluate) return postFair(std::move(queued));
  try {
    evaluateInline(queued.info, queued.sample->get().body._u.evaluate);
  } catch (const std::exception& e) {
    log.error("dds_request_failed", {{"method", rpc::toString(queued.info.method)}, {"error", e.what()}});
    replies.sendError(queued.info,
                      {StatusCode::Internal, std::string("robodiffd failed to handle the request: ") + e.what()});
  }
  scheduler.served(client, queued.info.quota->slot);
  done();
}

// At most limits.max_running_requests_per_client of a writer's posted requests are handed
// to the service at once; each one's end hands over the writer's next (FairScheduler).
void DdsServer::Core::postFair(Queued queued) {
  const std::uint64_t client = queued.info.publication;
  if (!scheduler.startPosted(client, queued)) return;
  post(std::move(queued.sample), std::move(queued.info));
}

void DdsServer::Core::handle(std::shared_ptr<WireRequest> sample, Clock::time_point received,
                             dds_instance_handle_t publication) {
  const robodiff_wire_Request& request = sample->get();
  RequestInfo info;
  info.publication = publication;
  info.header = dds_codec::fromWire(request.header);
  info.received = received;
  // Addressed to another server: it answers (several servers may share a domain).
  if (!info.header.server_instance_id.empty() && info.header.server_instance_id != service.instanceId()) return;
  // The reply goes to the caller partition of the request's publication; without one the
  // request cannot be answered, so it is not served (logged within the error budget).
  auto found = channels->forPublication(publication);
  if (!found.channel) {
    const auto d = unanswerable.note(publication, received);
    if (d.log)
      log.warn("dds_request_not_served", {{"client_id", info.header.client_id}, {"count", d.count},
                                          {"reason", found.problem}});
    return;
  }
  info.channel = std::move(found.channel);

  const auto method = dds_codec::methodFromWire(request.body._d);
  if (method) info.method = *method;
  if (info.method == rpc::Method::EvaluateBatch) info.knot_count = request.body._u.evaluate_batch.knot_count;
  ++in_flight;
  try {
    if (!accepting) {
      if (method)
        replies.sendError(info, {StatusCode::Unavailable, "robodiffd " + service.instanceId() +
                                                              " is draining (shutting down): it finishes the "
                                                              "requests in flight and takes no new ones; retry "
                                                              "with another server"});
      done();
      return;
    }
    if (Status admitted = service.admit(info.header); !admitted.ok()) {
      if (method) replies.sendError(info, admitted);
      done();
      return;
    }
    if (!method) {
      // An unknown discriminator (DDS usually drops such samples already: enum validation):
      // one log line per writer per second, replies within the error budget.
      const auto d = malformed.note(info.publication, received);
      if (d.log)
        log.warn("dds_request_unknown_method", {{"client_id", info.header.client_id}, {"count", d.count},
                                                {"dropped_unanswered", d.dropped},
                                                {"method", static_cast<std::uint64_t>(request.body._d)}});
      if (d.reply) replies.sendUnknownMethod(info, request.body._d);
      done();
      return;
    }
    enqueue(std::move(sample), std::move(info));
  } catch (const std::exception& e) {
    log.error("dds_request_failed", {{"method", rpc::toString(info.method)}, {"error", e.what()}});
    replies.sendError(info, {StatusCode::Internal, std::string("robodiffd failed to handle the request: ") + e.what()});
    done();
  }
}

// Evaluate on the receive thread: shape, size the reply, evaluate() straight into it.
void DdsServer::Core::evaluateInline(const RequestInfo& info, const robodiff_wire_EvaluateRequest& request) {
  const CallContext ctx = CallContext::from(info.header, "dds", info.received);
  const std::string_view function_id = request.function_id ? request.function_id : "";
  FunctionShape shape;
  if (Status status = service.shape(function_id, shape); !status.ok()) return replies.sendError(info, status);
  dds_codec::WireReply reply;
  reply->body._d = robodiff_wire_METHOD_EVALUATE;  // first: the union is freed by its discriminator
  dds_codec::allocDoubles(reply->body._u.evaluate.outputs, shape.output_count);
  const Status status = service.evaluate(ctx, function_id, dds_codec::view(request.inputs),
                                         dds_codec::view(reply->body._u.evaluate.outputs));
  if (!status.ok()) return replies.sendError(info, status);
  replies.header(info, status, reply->header);
  replies.send(info, reply.get(), StatusCode::Ok);
}

void DdsServer::Core::post(std::shared_ptr<WireRequest> sample, RequestInfo info) {
  // The task keeps the sample (its strings and doubles are read in place) and the shared
  // state; the token ends the request's in-flight count whether the task runs or is dropped.
  auto token = std::make_shared<InFlight>(shared_from_this(), info);
  ++waiting;
  const bool posted = service.post([core = shared_from_this(), sample, info, token] {
    --core->waiting;
    core->runPosted(sample->get(), info);
  });
  if (!posted) {
    const std::int64_t queued = --waiting;
    replies.sendError(info, {StatusCode::ResourceExhausted,
                             "request queue full (" + std::to_string(std::max<std::int64_t>(queued, 0)) +
                                 " waiting); retry later"});
  }
}

// A posted method, on one of the service's request threads.
void DdsServer::Core::runPosted(const robodiff_wire_Request& sample, const RequestInfo& info) {
  try {
    CallContext ctx = CallContext::from(info.header, "dds", info.received);
    ctx.caller = callers->of(info.publication);
    if (ctx.expired()) {
      const auto waited = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - info.received);
      return replies.sendError(info, {StatusCode::DeadlineExceeded,
                                      std::string(rpc::toString(info.method)) + " waited " +
                                          std::to_string(waited.count()) +
                                          " ms in robodiffd's request queue, past its deadline; not started"});
    }
    const auto& body = sample.body._u;
    // Decode, call the service, send its reply (or its error).
    auto serve = [&](const auto& wire, auto request, auto reply, auto method) {
      dds_codec::fromWire(wire, request);
      const Status status = (service.*method)(ctx, request, reply);
      return status.ok() ? replies.sendBody(info, reply) : replies.sendError(info, status);
    };
    switch (info.method) {
      case rpc::Method::LoadModel:
        return serve(body.load_model, rpc::LoadModelRequest{}, rpc::LoadModelReply{}, &ServiceApi::loadModel);
      case rpc::Method::GetFunction:
        return serve(body.get_function, rpc::GetFunctionRequest{}, rpc::GetFunctionReply{}, &ServiceApi::getFunction);
      case rpc::Method::ListFunctions:
        return serve(body.list_functions, rpc::ListFunctionsRequest{}, rpc::ListFunctionsReply{},
                     &ServiceApi::listFunctions);
      case rpc::Method::Health:
        return serve(body.health, rpc::HealthRequest{}, rpc::HealthReply{}, &ServiceApi::health);
      case rpc::Method::Release:
        return serve(body.release, rpc::ReleaseRequest{}, rpc::ReleaseReply{}, &ServiceApi::release);
      case rpc::Method::SubmitJob:
        return serve(body.submit_job, rpc::SubmitJobRequest{}, rpc::SubmitJobReply{}, &ServiceApi::submitJob);
      case rpc::Method::JobStatus:
        return serve(body.job_status, rpc::JobStatusRequest{}, rpc::JobStatusReply{}, &ServiceApi::jobStatus);
      case rpc::Method::CancelJob:
        return serve(body.cancel_job, rpc::CancelJobRequest{}, rpc::CancelJobReply{}, &ServiceApi::cancelJob);
      case rpc::Method::JobResult:
        return serve(body.job_result, rpc::JobResultRequest{}, rpc::JobResultReply{}, &ServiceApi::jobResult);
      case rpc::Method::QueryArtifact:
        return serve(body.query_artifact, rpc::QueryArtifactRequest{}, rpc::QueryArtifactReply{},
                     &ServiceApi::queryArtifact);
      case rpc::Method::FetchArtifactChunk:
        return serve(body.fetch_artifact_chunk, rpc::FetchArtifactChunkRequest{}, rpc::FetchArtifactChunkReply{},
                     &ServiceApi::fetchArtifactChunk);
      case rpc::Method::FleetStatus:
        return serve(body.fleet_status, rpc::FleetStatusRequest{}, rpc::FleetStatusReply{}, &ServiceApi::fleetStatus);
      case rpc::Method::EvaluateBatch: return evaluateBatch(info, body.evaluate_batch);
      case rpc::Method::Evaluate: break;  // inline, never posted
    }
  } catch (const std::exception& e) {
    log.error("dds_request_failed", {{"method", rpc::toString(info.method)}, {"error", e.what()}});
    replies.sendError(info, {StatusCode::Internal, std::string("robodiffd failed to handle the request: ") + e.what()});
  }
}

// EvaluateBatch: check that the sizes add up, evaluate into one buffer, reply in chunks
// that borrow slices of it.
void DdsServer::Core::evaluateBatch(const RequestInfo& info, const robodiff_wire_EvaluateBatchRequest& request) {
  const CallContext ctx = CallContext::from(info.header, "dds", info.received);
  const std::string_view function_id = request.function_id ? request.function_id : "";
  FunctionShape shape;
  if (Status status = service.shape(function_id, shape); !status.ok()) return replies.sendError(info, status);
  const std::uint64_t knots = request.knot_count;
  const std::span<const double> inputs = dds_codec::view(request.inputs);
  if (knots * shape.input_count != inputs.size())
    return replies.sendError(
        info, {StatusCode::InvalidArgument,
               "EvaluateBatch of " + std::string(function_id) + ": knot_count " + std::to_string(knots) + " x " +
                   std::to_string(shape.input_count) + " inputs per knot = " +
                   std::to_string(knots * shape.input_count) + " doubles, but the request carries " +
                   std::to_string(inputs.size())});
  if (shape.max_batch_knots != 0 && knots > shape.max_batch_knots)
    return replies.sendError(info, {StatusCode::ResourceExhausted,
                                    "EvaluateBatch of " + std::to_string(knots) + " knots: at most " +
                                        std::to_string(shape.max_batch_knots) +
                                        " knots per request; split the batch"});
  const std::size_t count = static_cast<std::size_t>(knots) * shape.output_count;
  std::unique_ptr<double[]> outputs(new double[count == 0 ? 1 : count]);
  const Status status = service.evaluateBatch(ctx, function_id, knots, inputs, std::span<double>(outputs.get(), count));
  if (!status.ok()) return replies.sendError(info, status);
  replies.sendBatch(info, shape.output_count, std::span<const double>(outputs.get(), count));
}

}  // namespace robodiff::server
