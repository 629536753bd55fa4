#pragma once
// Making a DDS Security keystore for robodiff (what `robodiff security` runs), like
// `ros2 security` does: one CA (ECDSA P-256) that issues the identity certificates and
// signs (S/MIME) the governance and every permissions document. Runs the `openssl` command.
// Layout (deploy/security.md):
//   <dir>/ca.cert.pem, <dir>/private/ca.key.pem (0600; keep it offline once identities exist)
//   <dir>/governance.xml, governance.p7s
//   <dir>/identities/<name>/cert.pem, key.pem (0600), permissions.xml, permissions.p7s

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace robodiff::client {

enum class IdentityRole {
  Client,    // publishes requests and reads replies, in partition robodiff.caller.<name> only
  Operator,  // a client in robodiff.operator.<name> (may act on others' jobs and functions);
             // its certificate also says OU=operators
  Server,    // reads requests and publishes replies in every caller partition
};

struct KeystoreOptions {
  std::string service_name = "robodiff";  // topics "<service>_request" and "<service>_reply"
  int valid_days = 3650;                  // certificates and permissions
  // Also encrypt the RTPS submessages around the data (heartbeats, acknowledgements) so
  // that no one on the path can forge them; the data is encrypted either way. Costs about
  // 2x the round-trip latency of open DDS instead of about 1.3x (deploy/security.md).
  bool protect_metadata = false;
  // A server identity that also calls these services as a client, in its own caller
  // partition: a fleet's robot host calling its build hosts (docs/fleet.md). One identity
  // for both, because Cyclone DDS 0.10's access control keeps one permissions document per
  // domain in a process (its participants cannot hold different ones).
  std::vector<std::string> also_calls;
};

// Creates the CA, the signed governance (all topics' data encrypted, discovery and
// liveliness encrypted, unauthenticated participants refused) and the server identity
// `server_name`. Throws std::runtime_error naming the openssl step that failed, or when
// `dir` already holds a keystore.
void initKeystore(const std::filesystem::path& dir, std::string_view server_name = "robodiffd",
                  const KeystoreOptions& options = {});

// Adds identity `name` (certificate, key, signed permissions for its role). Throws
// std::invalid_argument for a bad or existing name, std::runtime_error when openssl fails.
void addIdentity(const std::filesystem::path& dir, std::string_view name, IdentityRole role,
                 const KeystoreOptions& options = {});

// The certificate subject of an identity, as the permissions name it: "CN=alice,O=robodiff"
// ("CN=alice,OU=operators,O=robodiff" for an operator).
std::string identitySubject(std::string_view name, IdentityRole role);

}  // namespace robodiff::client
