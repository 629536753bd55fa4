#pragma once
// The server side of the Cyclone DDS transport. One receive thread waits on a waitset for
// requests on "<service>_request" and answers on "<service>_reply", each reply in the caller
// partition its request was published in (a reply writer per caller partition; a request
// from a publication in no caller partition is not served: dds_partitions.hpp):
//  - requests addressed to another server instance are dropped silently (it answers them);
//  - ServiceApi::admit() refusing a request is answered at once with its status;
//  - the others wait in their writer's lane (fair_scheduler.hpp): writers are served one
//    request each in turn; a writer with fair.max_queued pending is refused
//    RESOURCE_EXHAUSTED, and at most fair.max_running of its posted requests are in the
//    service at once;
//  - Evaluate runs inline on the receive thread (shape, then evaluate() straight into the
//    reply sample's buffer);
//  - every other method is handed to ServiceApi::post(); a full queue is answered
//    RESOURCE_EXHAUSTED at once;
//  - EvaluateBatch replies larger than max_sample_bytes are split at knot boundaries.
// Every reply is followed by ServiceApi::recordRequest("dds", ...).
//
// Lifetime: the ServiceApi and the Logger must outlive the service's request threads (posted
// tasks use them); the DdsServer itself may be destroyed while posted tasks still run (they
// share its state, and their replies are then dropped).

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "robodiff/schema/dds_topics.hpp"
#include "robodiff/server/log.hpp"
#include "robodiff/server/fair_scheduler.hpp"
#include "robodiff/server/service_api.hpp"

namespace robodiff::server {

struct DdsServerOptions {
  // DDS domain; the default is the domain CYCLONEDDS_URI configures (deploy/cyclonedds-*.xml).
  std::uint32_t domain_id = dds_codec::kDefaultDomain;
  // Topics "<service_name>_request" and "<service_name>_reply".
  std::string service_name = std::string(dds_codec::kDefaultServiceName);
  // The most bytes of doubles one EvaluateBatch reply sample carries; larger replies are
  // split into chunks (at least one knot each).
  std::size_t max_sample_bytes = 512 * 1024;
  // How long a reply write may block when the reply writer's history is full (slow readers).
  std::chrono::milliseconds write_blocking = std::chrono::seconds(1);
  // This participant's DDS lease: how soon clients notice that this server died without
  // saying goodbye (crash, SIGKILL) and fail their pending calls. 0: the configuration's
  // Discovery/LeaseDuration (10 s by default). A clean stop() is seen at once either way.
  std::chrono::milliseconds lease = std::chrono::seconds(1);
  // DDS Security identity (dds_codec::keystoreIdentity); none: an open participant that
  // any process reaching the domain may call.
  dds_codec::DdsSecurity security;
  // Per writer (client): requests pending and posted requests running at once (limits.*);
  // requests are served one per writer in turn (fair_scheduler.hpp).
  FairLimits fair;
  // Error replies per writer per second to unknown-method or over-quota requests; the
  // rest are dropped unanswered.
  std::uint32_t error_replies_per_second = 100;
};

class DdsServer {
 public:
  DdsServer(ServiceApi& service, DdsServerOptions options, Logger& log);
  ~DdsServer();  // stop()
  DdsServer(const DdsServer&) = delete;
  DdsServer& operator=(const DdsServer&) = delete;

  // Creates the DDS entities and starts the receive thread. Throws std::runtime_error naming
  // the DDS call, domain and topic when DDS refuses. Once only.
  void start();
  // From now on new requests are answered UNAVAILABLE ("draining"); in-flight ones finish.
  void stopAccepting();
  // Waits until no request is in flight (true) or the timeout passes (false).
  bool waitIdle(std::chrono::milliseconds timeout);
  // Stops the receive thread and deletes the DDS entities at once: clients see the server
  // go away. Replies of requests still running are dropped. Idempotent.
  void stop();

  // Readiness (robodiffd's /readyz): OK while started and not stopped, with the participant
  // and the request reader alive in Cyclone (dds_get_domainid, dds_get_status_changes:
  // microseconds); UNAVAILABLE naming what is not. Not concurrently with start() or stop().
  Status ready() const;
  // Requests taken and not yet answered (inline and posted).
  std::size_t inFlight() const;
  std::uint32_t domainId() const;           // the actual domain (the default resolved); after start()
  std::string requestTopic() const;
  std::string replyTopic() const;

  struct Core;  // shared with posted tasks (dds_server.cpp)

 private:
  std::shared_ptr<Core> core_;
};

}  // namespace robodiff::server
