#include "pmg/hal/bus/sil_emulator.hpp"

namespace pmg::hal::bus {

std::vector<std::unique_ptr<CanTransport>> makeHostUdpTransports(const BusPlan& plan, std::uint16_t base,
                                                                 std::unique_ptr<CanTransport>& imu_out) {
  const std::size_t nb = plan.buses().size();
  std::vector<std::unique_ptr<CanTransport>> out;
  for (std::size_t b = 0; b <= nb; ++b) {
    UdpCanTransport::Options o;
    o.local_port = udpPorts(base, nb, b).first;
    o.peer_port = udpPorts(base, nb, b).second;
    auto t = std::make_unique<UdpCanTransport>(o);
    if (b < nb) out.push_back(std::move(t));
    else imu_out = std::move(t);
  }
  return out;
}

}  // namespace pmg::hal::bus
