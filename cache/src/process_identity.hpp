// Who holds a claim: an owner token naming the host, the process and its start time
// (so a recycled pid is not mistaken for the owner), plus a random nonce per claim.
#pragma once

#include <string>

namespace robodiff::cache::detail {

// "host:pid:start-ticks:nonce" for the calling process, with a fresh nonce.
std::string newOwnerToken();

// False only when the owner is certainly dead: same host, and no process with that pid
// and start time. Owners on other hosts are presumed alive (their lease decides).
bool ownerMayBeAlive(const std::string& owner);

// The pid in an owner token (0 when malformed).
int ownerPid(const std::string& owner);

}  // namespace robodiff::cache::detail
