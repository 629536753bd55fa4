#pragma once
// The caller of an iceoryx request: the OS user running the client process. iceoryx 2.0
// carries no authenticated sender, so the client's id ("<host>:<pid>:<random>", its default:
// client/connection defaultClientId) names the process, and the owner of /proc/<pid> on this
// host is the caller. Advisory (deploy/security.md, "Ownership"): a process that can map
// RouDi's segments can write any id. Operators: root and the user robodiffd runs as.

#include <string_view>

#include "robodiff/server/service_api.hpp"

namespace robodiff::server::shm_detail {

// "user:<name>" ("user:uid<n>" without a passwd entry), operator for uid 0 and our euid;
// "shm:?unknown" (owner of nothing but its own) when the id names no live local process.
// Cached per client id. Safe from any thread.
Caller callerOfShmClient(std::string_view client_id);

// Whether the process a client id names ("<host>:<pid>:<random>" on this host) is gone.
// False when the id names no local process (nothing to tell).
bool shmClientProcessGone(std::string_view client_id);

// What callerOfShmClient uses: the caller of a uid.
Caller callerOfUid(unsigned uid);

}  // namespace robodiff::server::shm_detail
