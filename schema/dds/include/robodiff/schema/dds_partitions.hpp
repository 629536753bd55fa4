#pragma once
// Who calls over DDS, through the standard PARTITION QoS (deploy/security.md, "Ownership").
// A client writes its requests in its caller partition, and reads its replies there:
//   robodiff.caller.<name>     a client identity (`robodiff security add-client <name>`)
//   robodiff.operator.<name>   an operator identity (`add-client <name> --operator`)
// The server reads requests in both wildcard patterns and writes each reply in the
// partition of its request's publication (one reply writer per caller partition). Under DDS Security an identity's
// signed permissions allow it to publish requests only in its own partition, and the
// access-control plugin checks every remote writer's partition against them: the partition
// the server reads on a request's publication is the caller's proven identity. On open DDS
// the partition is "robodiff.caller.<OS user name>", only claimed.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace robodiff::dds_codec {

inline constexpr std::string_view kCallerPartitionPrefix = "robodiff.caller.";
inline constexpr std::string_view kOperatorPartitionPrefix = "robodiff.operator.";

// "robodiff.caller.alice", or "robodiff.operator.alice" for an operator.
std::string callerPartition(std::string_view name, bool operator_);
// The partition patterns a server reads requests in, and may write replies in: both
// prefixes followed by '*'.
std::vector<std::string> serverRequestPartitions();

// The partition an identity's signed permissions (permissions.p7s, S/MIME with the XML in
// clear) let it publish requests in. Throws std::invalid_argument naming the file when it
// grants none (a keystore made before callers had partitions: re-create the identity).
std::string permittedCallerPartition(const std::filesystem::path& permissions);

// The open-DDS caller partition: "robodiff.caller.<user>" for this process's effective uid
// (its passwd name, else "uid<n>"; characters other than letters, digits, '-', '_' and '.'
// become '_').
std::string openCallerPartition();

struct PartitionCaller {
  std::string name;  // "alice"
  bool operator_ = false;
};
// The caller a request partition names; nullopt for any other partition (another prefix,
// an empty name, or a name with a DDS wildcard character '*', '?', '[', ']' or a backslash).
std::optional<PartitionCaller> callerOfPartition(std::string_view partition);

}  // namespace robodiff::dds_codec
