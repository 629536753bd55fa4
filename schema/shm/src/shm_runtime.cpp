// The process-wide iceoryx runtime and the fast "is RouDi running" check.
#include "robodiff/schema/shm_runtime.hpp"

#include <grp.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <random>

#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/iceoryx_posh_types.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"

namespace robodiff::shm {
namespace {

std::mutex g_mutex;
std::atomic<bool> g_ready{false};

// connect() a socket of `type` to path: true when something is bound there.
bool canConnect(const std::string& path, int type, int& error) {
  const int fd = ::socket(AF_UNIX, type | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    error = errno;
    return false;
  }
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, path.c_str(), sizeof(address.sun_path) - 1);
  const bool ok = ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  error = ok ? 0 : errno;
  ::close(fd);
  return ok;
}

}  // namespace

std::string roudiSocketPath() { return std::string("/tmp/") + iox::roudi::IPC_CHANNEL_ROUDI_NAME; }

void removeRoudiLeftovers() {
  if (roudiRunning()) return;
  ::unlink(roudiSocketPath().c_str());
  ::shm_unlink("/iceoryx_mgmt");
  // The data segment is named after the user's group.
  if (const group* g = ::getgrgid(::getgid())) ::shm_unlink((std::string("/") + g->gr_name).c_str());
}

bool roudiRunning() {
  const std::string path = roudiSocketPath();
  if (::access(path.c_str(), F_OK) != 0) return false;
  int error = 0;
  if (canConnect(path, SOCK_DGRAM, error)) return true;
  // iceoryx uses datagrams; should a build use a stream socket, the type mismatch says so.
  if (error == EPROTOTYPE) return canConnect(path, SOCK_STREAM, error);
  return false;
}

void quietIceoryxLogs() {
  iox::log::LogManager::GetLogManager().SetDefaultLogLevel(iox::log::LogLevel::kWarn,
                                                          iox::log::LogLevelOutput::kHideLogLevel);
}

Status ensureRuntime(std::string_view name_prefix) {
  if (g_ready.load()) return {};
  std::lock_guard lock(g_mutex);
  if (g_ready.load()) return {};
  quietIceoryxLogs();
  if (!roudiRunning())
    return {StatusCode::Unavailable, "no iceoryx RouDi is running (nothing answers on " + roudiSocketPath() +
                                         "): start iox-roudi (deploy/roudi.toml) or robodiffd, which embeds one"};
  std::random_device random;
  char suffix[32];
  std::snprintf(suffix, sizeof suffix, "-%d-%06x", static_cast<int>(::getpid()), static_cast<unsigned>(random()) & 0xffffffu);
  std::string name = std::string(name_prefix.substr(0, 60)) + suffix;
  iox::runtime::PoshRuntime::initRuntime(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name.c_str()));
  g_ready = true;
  return {};
}

bool runtimeReady() { return g_ready.load(); }

}  // namespace robodiff::shm
