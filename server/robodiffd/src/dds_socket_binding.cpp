#include "dds_socket_binding.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>

#include "dds_exposure.hpp"

namespace robodiff::server {

namespace {

// The device holding `address` (an IPv4 or IPv6 literal), or "".
std::string deviceOfAddress(const std::string& address) {
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return {};
  std::string device;
  char text[INET6_ADDRSTRLEN];
  for (ifaddrs* a = list; a != nullptr && device.empty(); a = a->ifa_next) {
    if (a->ifa_addr == nullptr) continue;
    const int family = a->ifa_addr->sa_family;
    const void* raw = family == AF_INET    ? static_cast<const void*>(&reinterpret_cast<sockaddr_in*>(a->ifa_addr)->sin_addr)
                      : family == AF_INET6 ? static_cast<const void*>(&reinterpret_cast<sockaddr_in6*>(a->ifa_addr)->sin6_addr)
                                           : nullptr;
    if (raw != nullptr && ::inet_ntop(family, raw, text, sizeof text) != nullptr && address == text)
      device = a->ifa_name;
  }
  ::freeifaddrs(list);
  return device;
}

std::string describe(int fd) {
  sockaddr_storage local{};
  socklen_t size = sizeof local;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &size) != 0) return "udp ?";
  char text[INET6_ADDRSTRLEN] = "?";
  int port = 0;
  if (local.ss_family == AF_INET) {
    const auto& in = reinterpret_cast<const sockaddr_in&>(local);
    ::inet_ntop(AF_INET, &in.sin_addr, text, sizeof text);
    port = ntohs(in.sin_port);
  } else if (local.ss_family == AF_INET6) {
    const auto& in6 = reinterpret_cast<const sockaddr_in6&>(local);
    ::inet_ntop(AF_INET6, &in6.sin6_addr, text, sizeof text);
    port = ntohs(in6.sin6_port);
  }
  return std::string("udp ") + text + ":" + std::to_string(port);
}

// A UDP (IPv4 or IPv6) socket not bound to a device yet.
bool unboundUdpSocket(int fd) {
  int type = 0, domain = 0;
  socklen_t size = sizeof type;
  if (::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &size) != 0 || type != SOCK_DGRAM) return false;
  size = sizeof domain;
  if (::getsockopt(fd, SOL_SOCKET, SO_DOMAIN, &domain, &size) != 0 || (domain != AF_INET && domain != AF_INET6))
    return false;
  char bound[IFNAMSIZ] = {};
  size = sizeof bound;
  return ::getsockopt(fd, SOL_SOCKET, SO_BINDTODEVICE, bound, &size) == 0 && bound[0] == '\0';
}

}  // namespace

std::optional<std::string> cycloneSingleDevice(const char* uri) {
  if (cycloneLoopbackOnly(uri)) return "lo";
  std::set<std::string> devices;
  for (const CycloneInterface& i : cycloneInterfaces(uri)) {
    if (i.autodetermine) return std::nullopt;
    const std::string device = i.name.empty() ? deviceOfAddress(i.address) : i.name;
    if (device.empty()) return std::nullopt;
    devices.insert(device);
  }
  if (devices.size() != 1) return std::nullopt;
  return *devices.begin();
}

BoundSockets bindUdpSocketsToDevice(const std::string& device) {
  BoundSockets result;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    int fd = -1;
    try {
      fd = std::stoi(entry.path().filename().string());
    } catch (const std::exception&) {
      continue;
    }
    if (!unboundUdpSocket(fd)) continue;
    if (::setsockopt(fd, SOL_SOCKET, SO_BINDTODEVICE, device.c_str(), static_cast<socklen_t>(device.size())) != 0) {
      result.error = "SO_BINDTODEVICE " + device + " on " + describe(fd) + ": " + std::strerror(errno);
      return result;
    }
    result.sockets.push_back(describe(fd));
  }
  if (ec) result.error = "cannot list /proc/self/fd: " + ec.message();
  return result;
}

}  // namespace robodiff::server
