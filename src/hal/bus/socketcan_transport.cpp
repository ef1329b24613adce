#include "pmg/hal/bus/socketcan_transport.hpp"

#include <cerrno>
#include <cstring>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/netlink.h>
#include <linux/can/raw.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <system_error>

namespace pmg::hal::bus {

std::uint32_t errorClassFromLinux(const can_frame& f) noexcept {
  std::uint32_t m = 0;
  const canid_t id = f.can_id;
  if (id & CAN_ERR_BUSOFF) m |= kErrorBusOff;
  if (id & CAN_ERR_RESTARTED) m |= kErrorRestarted;
  if (id & CAN_ERR_TX_TIMEOUT) m |= kErrorTxTimeout;
  if (id & (CAN_ERR_PROT | CAN_ERR_ACK | CAN_ERR_BUSERROR)) m |= kErrorProtocol;
  if (id & CAN_ERR_CRTL) {
    const std::uint8_t c = f.can_dlc >= 2 ? f.data[1] : 0;
    if (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) m |= kErrorPassive;
    if (c & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) m |= kErrorRxOverflow;
  }
  return m;
}

std::size_t toLinux(const CanFrame& in, bool fd_socket, canfd_frame& out) noexcept {
  std::memset(&out, 0, sizeof out);
  if (in.error) return 0;
  if (in.extended ? in.id > CAN_EFF_MASK : in.id > CAN_SFF_MASK) return 0;
  out.can_id = in.id | (in.extended ? CAN_EFF_FLAG : 0u);
  if (in.fd) {
    if (!fd_socket || !isValidFdLength(in.len)) return 0;
    out.len = in.len;
    out.flags = in.brs ? CANFD_BRS : 0;
    std::memcpy(out.data, in.data.data(), in.len);
    return CANFD_MTU;
  }
  if (in.len > CAN_MAX_DLEN) return 0;
  out.len = in.len;
  std::memcpy(out.data, in.data.data(), in.len);
  return CAN_MTU;
}

bool fromLinux(const canfd_frame& in, std::size_t nbytes, CanFrame& out) noexcept {
  if (nbytes != CAN_MTU && nbytes != CANFD_MTU) return false;
  CanFrame f;
  if (in.can_id & CAN_ERR_FLAG) {
    can_frame cf;
    std::memcpy(&cf, &in, sizeof cf);
    f.error = true;
    f.id = errorClassFromLinux(cf);
    out = f;
    return true;
  }
  f.extended = in.can_id & CAN_EFF_FLAG;
  f.id = in.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  f.fd = nbytes == CANFD_MTU;
  f.brs = f.fd && (in.flags & CANFD_BRS);
  const std::size_t max = f.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN;
  f.len = static_cast<std::uint8_t>(in.len > max ? max : in.len);
  std::memcpy(f.data.data(), in.data, f.len);
  out = f;
  return true;
}

TxStatus txStatusFromErrno(int err) noexcept {
  switch (err) {
    case ENOBUFS:
    case EAGAIN: return TxStatus::kQueueFull;
    case ENETDOWN: return TxStatus::kBusOff;
    default: return TxStatus::kError;
  }
}

SocketCanTransport::SocketCanTransport(const std::string& ifname, bool fd) : fd_frames_(fd) {
  name_ = ifname;
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) {
    throw std::system_error(EINVAL, std::generic_category(),
                            "'" + ifname + "': interface name must have 1.." + std::to_string(IFNAMSIZ - 1) +
                                " characters");
  }
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    throw std::system_error(errno, std::generic_category(),
                            ifname + ": socket(PF_CAN) (is the kernel's can/can-raw module loaded?)");
  }
  auto fail = [&](const char* call) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw std::system_error(e, std::generic_category(), ifname + ": " + call);
  };
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, ifname.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &ifr) != 0) fail("SIOCGIFINDEX (no such CAN interface?)");
  ifindex_ = ifr.ifr_ifindex;
  if (fd) {
    const int on = 1;
    if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0) fail("CAN_RAW_FD_FRAMES");
  }
  const can_err_mask_t err_mask =
      CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED | CAN_ERR_TX_TIMEOUT | CAN_ERR_PROT | CAN_ERR_ACK;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0)
    fail("CAN_RAW_ERR_FILTER");
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex_;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) fail("bind");
  // Netlink socket for restart(); failure here is not fatal (restart() then returns false).
  nl_fd_ = ::socket(AF_NETLINK, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, NETLINK_ROUTE);
}

SocketCanTransport::~SocketCanTransport() {
  if (fd_ >= 0) ::close(fd_);
  if (nl_fd_ >= 0) ::close(nl_fd_);
}

TxStatus SocketCanTransport::send(const CanFrame& frame) noexcept {
  if (state_ == BusState::kBusOff) {
    ++counters_.tx_bus_off;
    return TxStatus::kBusOff;
  }
  canfd_frame lf;
  const std::size_t n = toLinux(frame, fd_frames_, lf);
  if (n == 0) {
    ++counters_.tx_errors;
    return TxStatus::kError;
  }
  const ssize_t r = ::send(fd_, &lf, n, MSG_DONTWAIT);
  if (r == static_cast<ssize_t>(n)) {
    ++counters_.tx_frames;
    return TxStatus::kOk;
  }
  const TxStatus s = r < 0 ? txStatusFromErrno(errno) : TxStatus::kError;
  if (s == TxStatus::kQueueFull) ++counters_.tx_queue_full;
  else if (s == TxStatus::kBusOff) ++counters_.tx_bus_off;
  else ++counters_.tx_errors;
  return s;
}

RxStatus SocketCanTransport::receive(CanFrame& out) noexcept {
  canfd_frame lf;
  for (;;) {
    const ssize_t n = ::recv(fd_, &lf, sizeof lf, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return RxStatus::kEmpty;
      if (errno == EINTR) continue;
      ++counters_.rx_errors;
      return RxStatus::kError;
    }
    if (!fromLinux(lf, static_cast<std::size_t>(n), out)) {
      ++counters_.rx_errors;
      return RxStatus::kError;
    }
    return acceptFrame(out);
  }
}

bool SocketCanTransport::restart() noexcept {
  ++counters_.restarts;
  if (nl_fd_ < 0) return false;
  // RTM_NEWLINK { ifinfomsg, IFLA_LINKINFO { IFLA_INFO_KIND "can", IFLA_INFO_DATA { IFLA_CAN_RESTART=1 } } }
  struct {
    nlmsghdr n;
    ifinfomsg i;
    char attrs[128];
  } req;
  std::memset(&req, 0, sizeof req);
  req.n.nlmsg_len = NLMSG_LENGTH(sizeof(ifinfomsg));
  req.n.nlmsg_type = RTM_NEWLINK;
  req.n.nlmsg_flags = NLM_F_REQUEST;
  req.n.nlmsg_seq = ++nl_seq_;
  req.i.ifi_family = AF_UNSPEC;
  req.i.ifi_index = ifindex_;
  auto put = [&req](unsigned short type, const void* data, std::size_t len) -> rtattr* {
    rtattr* a = reinterpret_cast<rtattr*>(reinterpret_cast<char*>(&req) + NLMSG_ALIGN(req.n.nlmsg_len));
    a->rta_type = type;
    a->rta_len = static_cast<unsigned short>(RTA_LENGTH(len));
    if (len) std::memcpy(RTA_DATA(a), data, len);
    req.n.nlmsg_len = NLMSG_ALIGN(req.n.nlmsg_len) + RTA_ALIGN(a->rta_len);
    return a;
  };
  auto end = [&req](rtattr* nest) {
    nest->rta_len = static_cast<unsigned short>(reinterpret_cast<char*>(&req) + req.n.nlmsg_len -
                                                reinterpret_cast<char*>(nest));
  };
  rtattr* linkinfo = put(IFLA_LINKINFO, nullptr, 0);
  put(IFLA_INFO_KIND, "can", 3);
  rtattr* data = put(IFLA_INFO_DATA, nullptr, 0);
  const std::uint32_t one = 1;
  put(IFLA_CAN_RESTART, &one, sizeof one);
  end(data);
  end(linkinfo);
  sockaddr_nl sa{};
  sa.nl_family = AF_NETLINK;
  const ssize_t r = ::sendto(nl_fd_, &req, req.n.nlmsg_len, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&sa), sizeof sa);
  return r == static_cast<ssize_t>(req.n.nlmsg_len);
}

}  // namespace pmg::hal::bus
