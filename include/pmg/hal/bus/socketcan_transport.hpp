#pragma once
/// @file socketcan_transport.hpp
/// @brief Linux SocketCAN raw socket, one per bus: non-blocking, CAN FD capable, error frames on.
///
/// Setup (constructor): socket(PF_CAN, SOCK_RAW, CAN_RAW), CAN_RAW_FD_FRAMES if `fd`,
/// CAN_RAW_ERR_FILTER = bus-off | controller | restarted | tx-timeout | protocol, O_NONBLOCK, bind.
/// A netlink socket is opened too so restart() can send IFLA_CAN_RESTART without allocating.
/// Interface bring-up (bitrate, `restart-ms`, txqueuelen) is the system's job:
///   ip link set can0 type can bitrate 1000000 restart-ms 100 && ip link set can0 txqueuelen 1000 up
/// restart() needs CAP_NET_ADMIN; without it rely on the kernel's restart-ms auto-recovery.

#include <cstdint>
#include <string>

#include "pmg/hal/bus/transport.hpp"

struct can_frame;
struct canfd_frame;

namespace pmg::hal::bus {

/// Map a Linux error frame (CAN_ERR_FLAG set) to an ErrorClass mask.
std::uint32_t errorClassFromLinux(const can_frame& frame) noexcept;
/// pmg frame -> Linux frame; returns the number of bytes to write (CAN_MTU or CANFD_MTU), 0 if the
/// frame is invalid (length, id width, FD on a classic socket).
std::size_t toLinux(const CanFrame& in, bool fd_socket, canfd_frame& out) noexcept;
/// Linux frame of `nbytes` (CAN_MTU or CANFD_MTU) -> pmg frame; false on a short read.
bool fromLinux(const canfd_frame& in, std::size_t nbytes, CanFrame& out) noexcept;
/// send() errno -> status (ENOBUFS/EAGAIN: queue full; ENETDOWN: bus-off/down; else error).
TxStatus txStatusFromErrno(int err) noexcept;

class SocketCanTransport final : public CanTransport {
 public:
  /// Opens and binds `ifname`. Throws std::system_error whose message names the interface and the
  /// failing call (e.g. "can0: bind: No such device"; "socket(PF_CAN): Address family not supported
  /// by protocol" when the kernel has no CAN support).
  SocketCanTransport(const std::string& ifname, bool fd);
  ~SocketCanTransport() override;

  TxStatus send(const CanFrame& frame) noexcept override;
  RxStatus receive(CanFrame& out) noexcept override;
  bool restart() noexcept override;
  int pollFd() const noexcept override { return fd_; }

 private:
  int fd_ = -1;
  int nl_fd_ = -1;
  int ifindex_ = 0;
  bool fd_frames_ = false;
  std::uint32_t nl_seq_ = 0;
};

}  // namespace pmg::hal::bus
