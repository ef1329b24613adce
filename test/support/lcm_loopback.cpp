#include "lcm_loopback.hpp"

#include <cstdint>

#include <lcm/lcm-cpp.hpp>

namespace pmg::test {

std::string lcmMulticastUnavailable(const std::string& url) {
  lcm::LCM tx(url);
  if (!tx.good()) return "LCM cannot open " + url + " on this machine";
  lcm::LCM probe(url);
  if (!probe.good()) return "LCM cannot open " + url + " on this machine";
  bool heard = false;
  struct Probe {
    static void on(const lcm::ReceiveBuffer*, const std::string&, bool* h) { *h = true; }
  };
  probe.subscribeFunction("PMG_TEST_PROBE", &Probe::on, &heard);
  const std::uint8_t byte = 1;
  for (int i = 0; i < 5 && !heard; ++i) {
    tx.publish("PMG_TEST_PROBE", &byte, 1);
    probe.handleTimeout(100);
  }
  return heard ? "" : "LCM multicast does not loop back on this machine (no multicast route): " + url;
}

}  // namespace pmg::test
