#pragma once
// DDS Security (OMG DDS Security 1.1) for a robodiff participant: the files of one identity
// and the QoS properties that load Cyclone's authentication, access-control and crypto
// plugins with them. Keystores are made by `robodiff security` (layout in deploy/security.md):
//   <keystore>/ca.cert.pem                 identity CA and permissions CA (one CA)
//   <keystore>/governance.p7s              signed governance (what is protected)
//   <keystore>/identities/<name>/cert.pem, key.pem, permissions.p7s

#include <dds/dds.h>

#include <filesystem>
#include <string>
#include <string_view>

namespace robodiff::dds_codec {

struct DdsSecurity {
  std::filesystem::path identity_ca;     // verifies the peers' identity certificates
  std::filesystem::path certificate;     // this participant's identity certificate
  std::filesystem::path private_key;     // its private key
  std::filesystem::path permissions_ca;  // verifies governance and permissions signatures
  std::filesystem::path governance;      // signed governance document (.p7s)
  std::filesystem::path permissions;     // signed permissions of this identity (.p7s)

  bool enabled() const { return !certificate.empty(); }
  // "identity alice of keystore /etc/robodiff/keystore" (for logs and errors).
  std::string describe() const;
};

// The identity `name` of a keystore made by `robodiff security`. Throws
// std::invalid_argument naming the missing file.
DdsSecurity keystoreIdentity(const std::filesystem::path& keystore, std::string_view name);

// "<keystore>/<identity>" (the ROBODIFF_DDS_SECURITY form): the last path component is the
// identity. Throws std::invalid_argument when it has no identity or a file is missing.
DdsSecurity securityFromSpec(std::string_view spec);

// The directory holding libdds_security_{auth,ac,crypto}.so: next to the loaded libddsc, or
// its Debian subdirectory libddsc0debian/. Throws std::runtime_error when not found.
std::filesystem::path securityPluginDir();

// Sets the dds.sec.* properties on a participant QoS. Throws what securityPluginDir throws.
void applySecurity(dds_qos_t* qos, const DdsSecurity& security);

}  // namespace robodiff::dds_codec
