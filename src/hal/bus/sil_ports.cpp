#include "pmg/hal/bus/sil_emulator.hpp"

#include <iterator>

namespace pmg::hal::bus {

std::vector<std::unique_ptr<UdpCanTransport>> makeUdpTransports(const BusPlan& plan, std::uint16_t base,
                                                                UdpSide side, std::unique_ptr<UdpCanTransport>& imu_out) {
  const std::size_t nb = plan.buses().size();
  std::vector<std::unique_ptr<UdpCanTransport>> out;
  for (std::size_t b = 0; b <= nb; ++b) {
    const auto ports = udpPorts(base, nb, b);  // (host port, SIL port)
    UdpCanTransport::Options o;
    o.local_port = side == UdpSide::kHost ? ports.first : ports.second;
    o.peer_port = side == UdpSide::kHost ? ports.second : ports.first;
    auto t = std::make_unique<UdpCanTransport>(o);
    if (b < nb) out.push_back(std::move(t));
    else imu_out = std::move(t);
  }
  return out;
}

std::vector<std::unique_ptr<CanTransport>> makeHostUdpTransports(const BusPlan& plan, std::uint16_t base,
                                                                 std::unique_ptr<CanTransport>& imu_out) {
  std::unique_ptr<UdpCanTransport> imu;
  auto udp = makeUdpTransports(plan, base, UdpSide::kHost, imu);
  imu_out = std::move(imu);
  return {std::make_move_iterator(udp.begin()), std::make_move_iterator(udp.end())};
}

}  // namespace pmg::hal::bus
