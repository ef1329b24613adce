#pragma once
// Whether LCM multicast loops back on this machine: tests that publish and receive over LCM skip
// (GTEST_SKIP() << why) where it does not (sandboxes without a multicast route drop it).
#include <string>

namespace pmg::test {

/// "" when a probe published on @p url is heard back on @p url within 0.5 s, else why not.
std::string lcmMulticastUnavailable(const std::string& url);

}  // namespace pmg::test
