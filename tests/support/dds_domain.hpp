// DDS domains for test processes. ctest runs several test processes at once, and two
// servers on one domain answer each other's clients; so each process claims its domains
// with an flock on a file under the temporary directory, held until it exits, and no
// two running test processes ever share one.
#pragma once

#include <cstdint>

namespace robodiff::testing {

// Claims a domain of first..last that no running process has claimed; throws when every
// one is taken. The claim lasts as long as this process.
std::uint32_t claimDdsDomain(std::uint32_t first, std::uint32_t last);

// This process's domain, fixed at the first call (a forked child keeps its parent's).
// Band 0 is 1..200; band 1 is 201..229, for a test that leaves a dead participant behind
// until its lease expires. ROBODIFF_TEST_DDS_DOMAIN, when set, names band 0's instead
// (the fleet tests take 230, which no claim hands out).
std::uint32_t testDomain(int band = 0);

// A further domain of 1..200 claimed by this process, on which no test runs a server:
// for a test that needs "no robodiffd there".
std::uint32_t emptyTestDomain();

}  // namespace robodiff::testing
