// Topic names, QoS and the entities of either side of the DDS transport.
#include "robodiff/schema/dds_topics.hpp"

#include <stdexcept>

#include "robodiff.h"
#include "robodiff/schema/dds_domain.hpp"
#include "robodiff/schema/dds_partitions.hpp"

namespace robodiff::dds_codec {

std::string requestTopicName(std::string_view service) { return std::string(service) + "_request"; }
std::string replyTopicName(std::string_view service) { return std::string(service) + "_reply"; }

namespace {

// The requests' partitions: the client's caller partition (its permissions' under DDS
// Security, its user's on open DDS), or every caller partition for the server.
std::vector<std::string> partitionsOfRequests(DdsEndpoints::Side side, const DdsSecurity& security,
                                              const std::string& caller_partition) {
  if (side == DdsEndpoints::Side::Server) return serverRequestPartitions();
  if (!caller_partition.empty()) return {caller_partition};
  return {security.enabled() ? permittedCallerPartition(security.permissions) : openCallerPartition()};
}

void setPartitions(dds_qos_t* qos, const std::vector<std::string>& partitions) {
  std::vector<const char*> names;
  for (const std::string& p : partitions) names.push_back(p.c_str());
  dds_qset_partition(qos, static_cast<uint32_t>(names.size()), names.data());
}

}  // namespace

std::string ddsError(std::string_view call, dds_return_t code) {
  return std::string(call) + " failed: " + dds_strretcode(code) + " (" + std::to_string(code) + ")";
}

DdsEndpoints::DdsEndpoints(std::uint32_t domain_id, std::string_view service, Side side,
                           std::chrono::milliseconds writer_blocking, std::chrono::milliseconds lease,
                           const DdsSecurity& security, const std::string& caller_partition) {
  const std::string where = [&] {
    return domain_id == kDefaultDomain ? std::string("the default DDS domain")
                                       : "DDS domain " + std::to_string(domain_id);
  }();
  dds_qos_t* participant_qos = dds_create_qos();
  if (lease.count() > 0) dds_qset_liveliness(participant_qos, DDS_LIVELINESS_AUTOMATIC, DDS_MSECS(lease.count()));
  try {
    if (security.enabled()) applySecurity(participant_qos, security);
  } catch (...) {
    dds_delete_qos(participant_qos);
    throw;
  }
  try {
    request_partitions_ = partitionsOfRequests(side, security, caller_partition);
    domain_id = prepareDomain(domain_id);
  } catch (...) {
    dds_delete_qos(participant_qos);
    throw;
  }
  participant_ = dds_create_participant(domain_id, participant_qos, nullptr);
  dds_delete_qos(participant_qos);
  if (participant_ < 0)
    throw std::runtime_error(ddsError("dds_create_participant", participant_) + " on " + where +
                             (security.enabled() ? " with DDS security (" + security.describe() +
                                                       "): a certificate, key, governance or permissions file "
                                                       "was refused (expired, tampered, or signed by another CA?)"
                                                 : std::string(" (check CYCLONEDDS_URI)")));
  dds_domainid_t actual = 0;
  domain_id_ = dds_get_domainid(participant_, &actual) == DDS_RETCODE_OK ? actual : domain_id;

  const std::string request_topic = requestTopicName(service), reply_topic = replyTopicName(service);
  qos_ = dds_create_qos();
  dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, DDS_MSECS(writer_blocking.count()));
  dds_qset_history(qos_, DDS_HISTORY_KEEP_ALL, 0);
  std::string failure;
  const dds_entity_t requests = dds_create_topic(participant_, &robodiff_wire_Request_desc, request_topic.c_str(), qos_, nullptr);
  reply_topic_entity_ = dds_create_topic(participant_, &robodiff_wire_Reply_desc, reply_topic.c_str(), qos_, nullptr);
  if (requests < 0) {
    failure = ddsError("dds_create_topic", requests) + " for topic " + request_topic;
  } else if (reply_topic_entity_ < 0) {
    failure = ddsError("dds_create_topic", reply_topic_entity_) + " for topic " + reply_topic;
  } else {
    const bool server = side == Side::Server;
    reader_topic_ = server ? request_topic : reply_topic;
    writer_topic_ = server ? reply_topic : request_topic;
    // Requests and a client's replies travel in partitions; a server makes its reply
    // writers, one per caller partition, with createReplyWriter().
    dds_qos_t* partitioned = dds_create_qos();
    dds_copy_qos(partitioned, qos_);
    setPartitions(partitioned, request_partitions_);
    reader_ = dds_create_reader(participant_, server ? requests : reply_topic_entity_, partitioned, nullptr);
    if (!server) writer_ = dds_create_writer(participant_, requests, partitioned, nullptr);
    dds_delete_qos(partitioned);
    if (reader_ < 0) failure = ddsError("dds_create_reader", reader_) + " for topic " + reader_topic_;
    else if (writer_ < 0) failure = ddsError("dds_create_writer", writer_) + " for topic " + writer_topic_;
    if (!failure.empty() && security.enabled())
      failure += " in partition " + request_partitions_.front() + " (does " + security.describe() +
                 " grant it? `robodiff security` writes the grants; identities made before replies had "
                 "partitions must be made again)";
  }
  if (!failure.empty()) {
    dds_delete_qos(qos_);
    qos_ = nullptr;
    dds_delete(participant_);
    throw std::runtime_error(failure + " on " + where);
  }
}

dds_entity_t DdsEndpoints::createReplyWriter(const std::string& partition) const {
  dds_qos_t* qos = dds_create_qos();
  dds_copy_qos(qos, qos_);
  setPartitions(qos, {partition});
  const dds_entity_t writer = dds_create_writer(participant_, reply_topic_entity_, qos, nullptr);
  dds_delete_qos(qos);
  return writer;
}

DdsEndpoints::~DdsEndpoints() {
  if (participant_ > 0) dds_delete(participant_);
  if (qos_) dds_delete_qos(qos_);
}

}  // namespace robodiff::dds_codec
