// The CPU priority of the service's background threads (request threads, batch helpers):
// a Linux nice value per thread, so that under a full CPU the transports' receive threads,
// which serve Evaluate inline, run before the posted work of a client flooding expensive
// requests. Without contention the nice value changes nothing.
#pragma once

namespace robodiff::server::detail {

// Makes the calling thread `increment` nicer (0: unchanged). Best effort: false when the
// kernel refused (a thread may always lower its own priority, so only odd sandboxes).
bool lowerCallingThreadPriority(unsigned increment);

}  // namespace robodiff::server::detail
