#pragma once
// The two topics of a robodiff service on Cyclone DDS and the entities each side needs:
// "<service>_request" (robodiff::wire::Request, clients write, servers read) and
// "<service>_reply" (robodiff::wire::Reply, servers write, clients read). QoS on both:
// RELIABLE and KEEP_ALL, so that no request or reply is dropped for lack of history.
// Requests and replies travel in caller partitions (dds_partitions.hpp): a client writes
// requests and reads replies in its own; the server reads requests in all of them and
// answers each in its request's partition (a reply writer per caller partition).

#include <dds/dds.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "robodiff/schema/dds_security.hpp"

namespace robodiff::dds_codec {

// DDS_DOMAIN_DEFAULT: the domain that CYCLONEDDS_URI configures (0 unless it says otherwise;
// without CYCLONEDDS_URI, domain 0 on loopback: dds_domain.hpp).
inline constexpr std::uint32_t kDefaultDomain = 0xFFFFFFFFu;
inline constexpr std::string_view kDefaultServiceName = "robodiff";

std::string requestTopicName(std::string_view service);  // "<service>_request"
std::string replyTopicName(std::string_view service);    // "<service>_reply"

// "dds_create_topic failed: Bad Parameter (-3)".
std::string ddsError(std::string_view call, dds_return_t code);

// A participant with both topics and a reader: the server reads requests, the client
// replies. A client also has its request writer; a server makes its reply writers with
// createReplyWriter(). Deleting the participant deletes the rest.
class DdsEndpoints {
 public:
  enum class Side { Server, Client };
  // Throws std::runtime_error naming the DDS call, the domain and the topic on failure.
  // writer_blocking: how long dds_write may block when the writer's history is full.
  // lease: the participant's lease duration (how soon peers notice this process died);
  // 0 keeps the configuration's (Discovery/LeaseDuration, 10 s by default).
  // security: DDS Security identity of the participant (none: an open participant).
  // caller_partition: a client's request partition; empty: the one its permissions grant
  // (DDS Security), else its OS user's (open DDS).
  DdsEndpoints(std::uint32_t domain_id, std::string_view service, Side side,
               std::chrono::milliseconds writer_blocking = std::chrono::seconds(1),
               std::chrono::milliseconds lease = std::chrono::milliseconds(0), const DdsSecurity& security = {},
               const std::string& caller_partition = {});
  ~DdsEndpoints();
  DdsEndpoints(const DdsEndpoints&) = delete;
  DdsEndpoints& operator=(const DdsEndpoints&) = delete;

  dds_entity_t participant() const { return participant_; }
  dds_entity_t reader() const { return reader_; }
  dds_entity_t writer() const { return writer_; }  // a client's request writer; 0 for a server
  // A reply writer in `partition` (a server's, one per caller partition), or a negative DDS
  // return code (under DDS Security: the permissions do not grant the partition).
  dds_entity_t createReplyWriter(const std::string& partition) const;
  std::uint32_t domainId() const { return domain_id_; }  // the actual id (the default resolved)
  const std::string& writerTopic() const { return writer_topic_; }
  const std::string& readerTopic() const { return reader_topic_; }
  // The partitions of the request writer and reply reader (client), or the request reader (server).
  const std::vector<std::string>& requestPartitions() const { return request_partitions_; }

 private:
  dds_entity_t participant_ = 0, reader_ = 0, writer_ = 0, reply_topic_entity_ = 0;
  dds_qos_t* qos_ = nullptr;  // both topics' QoS (reliable, keep all)
  std::uint32_t domain_id_ = 0;
  std::string writer_topic_, reader_topic_;
  std::vector<std::string> request_partitions_;
};

}  // namespace robodiff::dds_codec
