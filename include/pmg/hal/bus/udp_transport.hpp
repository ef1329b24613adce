#pragma once
/// @file udp_transport.hpp
/// @brief CAN over UDP datagrams on loopback: a userspace stand-in for a CAN bus, used by the tests
/// and by the `pmg_sil` motor-driver emulator (this machine has no CAN kernel module).
///
/// Each endpoint binds `local_port` on `host` and sends to `peer_port`; one datagram = one frame:
///   byte 0..1 magic 'P','C' | 2 version (1) | 3 flags (bit0 FD, bit1 BRS, bit2 extended id,
///   bit3 error indication) | 4 payload length | 5..7 zero | 8..11 id (little-endian) | 12.. payload.
/// An error datagram carries an ErrorClass mask in `id`; this is how the SIL injects bus-off.
/// While bus-off, send() drops frames and answers TxStatus::kBusOff until restart(), which sends a
/// kErrorRestarted indication to the peer (the emulated controller's recovery).

#include <cstdint>
#include <string>

#include "pmg/hal/bus/transport.hpp"

namespace pmg::hal::bus {

/// Size of the datagram header [bytes].
inline constexpr std::size_t kUdpCanHeader = 12;

/// Serialize a frame into `buf` (>= kUdpCanHeader + 64 bytes). Returns the datagram length.
std::size_t encodeUdpCan(const CanFrame& frame, std::uint8_t* buf) noexcept;
/// Parse a datagram; false if the magic, version, length, flags or reserved bytes (5..7, zero) are invalid.
bool decodeUdpCan(const std::uint8_t* buf, std::size_t n, CanFrame& out) noexcept;

class UdpCanTransport final : public CanTransport {
 public:
  struct Options {
    std::string host = "127.0.0.1";  ///< IPv4 address to bind and send to.
    std::uint16_t local_port = 0;    ///< Port this endpoint receives on (0: kernel picks, see localPort()).
    std::uint16_t peer_port = 0;     ///< Port of the other endpoint (may be set later with setPeerPort()).
    int rcvbuf_bytes = 1 << 20;      ///< SO_RCVBUF request [bytes].
  };
  /// Binds the socket (non-blocking). Throws std::system_error naming host:port on failure.
  explicit UdpCanTransport(const Options& options);
  ~UdpCanTransport() override;

  TxStatus send(const CanFrame& frame) noexcept override;
  RxStatus receive(CanFrame& out) noexcept override;
  bool restart() noexcept override;
  int pollFd() const noexcept override { return fd_; }

  /// Port actually bound.
  std::uint16_t localPort() const noexcept { return local_port_; }
  /// Change the destination port (setup).
  void setPeerPort(std::uint16_t port) noexcept;
  /// Send an error indication (ErrorClass mask) to the peer: used by the SIL to inject bus-off.
  bool sendErrorIndication(std::uint32_t mask) noexcept;

 private:
  int fd_ = -1;
  std::uint16_t local_port_ = 0;
  std::uint32_t addr_be_ = 0;
  std::uint16_t peer_port_ = 0;
};

}  // namespace pmg::hal::bus
