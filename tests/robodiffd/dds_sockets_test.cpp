// robodiffd's DDS sockets confined to the configured interface: Cyclone DDS 0.10 binds
// them to 0.0.0.0, so without SO_BINDTODEVICE a packet from another network reaches its
// RTPS parser. Checked with the kernel's view (ss) of a real robodiffd, and with a packet
// sent from a second network namespace over a veth pair.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <string>

#include "dds_socket_binding.hpp"
#include "robodiffd/robodiffd_process.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::testing {
namespace {

using server::bindUdpSocketsToDevice;
using server::cycloneSingleDevice;

TEST(DdsSockets, TheDeviceComesFromTheCycloneConfiguration) {
  EXPECT_EQ(cycloneSingleDevice(nullptr), "lo");  // the embedded loopback configuration
  EXPECT_EQ(cycloneSingleDevice("<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
                                "</Interfaces></General></Domain></CycloneDDS>"),
            "lo");
  EXPECT_EQ(cycloneSingleDevice("<CycloneDDS><NetworkInterface name=\"enp3s0\" multicast=\"false\"/></CycloneDDS>"),
            "enp3s0");
  EXPECT_EQ(cycloneSingleDevice("<CycloneDDS><NetworkInterface autodetermine=\"true\"/></CycloneDDS>"), std::nullopt);
  EXPECT_EQ(cycloneSingleDevice("<CycloneDDS><NetworkInterface name=\"eth0\"/><NetworkInterface name=\"eth1\"/>"
                                "</CycloneDDS>"),
            std::nullopt);
  EXPECT_EQ(cycloneSingleDevice("<CycloneDDS><NetworkInterface address=\"203.0.113.77\"/></CycloneDDS>"),
            std::nullopt);  // no device has that address
}

int udpSocket(int& port) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in any{};
  any.sin_family = AF_INET;
  ::bind(fd, reinterpret_cast<sockaddr*>(&any), sizeof any);
  socklen_t size = sizeof any;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&any), &size);
  port = ntohs(any.sin_port);
  return fd;
}

bool receives(int fd) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, 1000) == 1;
}

// A second network namespace joined to this one by a veth pair; removed at the end.
struct PeerNamespace {
  std::string name = "rdsock" + std::to_string(::getpid() % 100000);
  std::string host_address = "10.231.7.1", peer_address = "10.231.7.2";
  bool ok = false;
  PeerNamespace() {
    const std::string a = "rdva" + std::to_string(::getpid() % 100000), b = "rdvb" + std::to_string(::getpid() % 100000);
    ok = runCommand("( ip netns add " + name + " && ip link add " + a + " type veth peer name " + b + " && ip link set " +
                    b + " netns " + name + " && ip addr add " + host_address + "/30 dev " + a + " && ip link set " + a +
                    " up && ip netns exec " + name + " ip addr add " + peer_address + "/30 dev " + b +
                    " && ip netns exec " + name + " ip link set " + b + " up )")
             .exit_code == 0;
  }
  ~PeerNamespace() { runCommand("ip netns del " + name); }
  void send(int port) const {
    runCommand("ip netns exec " + name + " bash -c 'echo probe > /dev/udp/" + host_address + "/" +
               std::to_string(port) + "'");
  }
};

TEST(DdsSockets, ASocketBoundToLoopbackDropsAPacketFromAnotherNetwork) {
  PeerNamespace peer;
  if (!peer.ok) GTEST_SKIP() << "needs root and `ip netns` to make a second network";
  int confined_port = 0, open_port = 0;
  const int confined = udpSocket(confined_port);
  const auto bound = bindUdpSocketsToDevice("lo");
  ASSERT_TRUE(bound.error.empty()) << bound.error;
  EXPECT_FALSE(bound.sockets.empty());
  const int open = udpSocket(open_port);  // made after: not confined, the control

  peer.send(confined_port);
  peer.send(open_port);
  EXPECT_TRUE(receives(open)) << "the control socket should get the peer's packet (veth set-up broken?)";
  EXPECT_FALSE(receives(confined)) << "a socket confined to lo received a packet from another network";
  ::close(confined);
  ::close(open);
}

TEST(DdsSockets, RobodiffdConfinesItsDdsSocketsToLoopbackByDefault) {
  TempDir dir;
  RobodiffdProcess server(dir / "cache", dir / "robodiffd.log", {"--no-iceoryx", "--no-http"});
  ASSERT_TRUE(server.running());
  const auto confined = logEvent(server.log(), "dds_sockets_confined");
  ASSERT_FALSE(confined.is_null()) << server.log();
  EXPECT_EQ(confined["device"], "lo");
  // The kernel's view: every UDP socket of robodiffd is bound to lo ("addr%lo:port").
  const ProcessResult ss = runCommand("ss -H -u -a -n -p");
  ASSERT_EQ(ss.exit_code, 0) << ss.err;
  int sockets = 0;
  std::istringstream lines(ss.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("pid=" + std::to_string(server.pid()) + ",") == std::string::npos) continue;
    ++sockets;
    EXPECT_NE(line.find("%lo:"), std::string::npos) << line;
  }
  EXPECT_GE(sockets, 2) << ss.out;  // discovery and data, at least
  EXPECT_EQ(server.terminate(std::chrono::seconds(30)), 0) << server.log();
}

}  // namespace
}  // namespace robodiff::testing
