#pragma once
// Confining robodiffd's DDS sockets to the configured network interface. Cyclone DDS 0.10
// binds its unicast receive sockets to the wildcard address (0.0.0.0:port) whatever
// interfaces its configuration names, so packets from any network reach its RTPS parser.
// Once the participant exists, robodiffd binds each of the process's UDP sockets to the
// configured device with SO_BINDTODEVICE (no privilege needed on Linux >= 5.7 for a
// socket not bound to a device yet): the kernel then drops what arrives on any other
// interface. One device only; for several, deploy/security.md has the systemd setting.
#include <optional>
#include <string>
#include <vector>

namespace robodiff::server {

// The one network device the Cyclone configuration `uri` (CYCLONEDDS_URI's value) confines
// DDS to: "lo" when unset (robodiff's embedded loopback configuration) or when every
// interface is loopback; the device named, or owning the address given, when every
// <NetworkInterface> designates the same one. nullopt otherwise (autodetermine, several
// devices, an address no device has).
std::optional<std::string> cycloneSingleDevice(const char* uri);

struct BoundSockets {
  std::vector<std::string> sockets;  // "udp 0.0.0.0:7410" each
  std::string error;                 // empty on success
};

// Binds every UDP socket of this process not yet bound to a device to `device`.
BoundSockets bindUdpSocketsToDevice(const std::string& device);

}  // namespace robodiff::server
