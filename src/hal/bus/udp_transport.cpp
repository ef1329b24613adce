#include "pmg/hal/bus/udp_transport.hpp"

#include <arpa/inet.h>
#include <cerrno>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <system_error>

namespace pmg::hal::bus {

namespace {
constexpr std::uint8_t kMagic0 = 'P';
constexpr std::uint8_t kMagic1 = 'C';
constexpr std::uint8_t kVersion = 1;
enum : std::uint8_t { kFlagFd = 1, kFlagBrs = 2, kFlagExt = 4, kFlagErr = 8 };
}  // namespace

std::size_t encodeUdpCan(const CanFrame& f, std::uint8_t* buf) noexcept {
  const std::size_t len = f.len > kCanFdMaxPayload ? kCanFdMaxPayload : f.len;
  buf[0] = kMagic0;
  buf[1] = kMagic1;
  buf[2] = kVersion;
  buf[3] = static_cast<std::uint8_t>((f.fd ? kFlagFd : 0) | (f.brs ? kFlagBrs : 0) | (f.extended ? kFlagExt : 0) |
                                     (f.error ? kFlagErr : 0));
  buf[4] = static_cast<std::uint8_t>(len);
  buf[5] = buf[6] = buf[7] = 0;
  for (int i = 0; i < 4; ++i) buf[8 + i] = static_cast<std::uint8_t>(f.id >> (8 * i));
  std::memcpy(buf + kUdpCanHeader, f.data.data(), len);
  return kUdpCanHeader + len;
}

bool decodeUdpCan(const std::uint8_t* buf, std::size_t n, CanFrame& out) noexcept {
  if (n < kUdpCanHeader || buf[0] != kMagic0 || buf[1] != kMagic1 || buf[2] != kVersion) return false;
  const std::uint8_t flags = buf[3];
  const std::size_t len = buf[4];
  if ((flags & ~(kFlagFd | kFlagBrs | kFlagExt | kFlagErr)) != 0) return false;
  if (buf[5] != 0 || buf[6] != 0 || buf[7] != 0) return false;  // reserved bytes: a foreign or corrupt datagram
  if (n != kUdpCanHeader + len) return false;
  const bool fd = flags & kFlagFd;
  if (fd ? !isValidFdLength(len) : len > kCanMaxPayload) return false;
  CanFrame f;
  f.fd = fd;
  f.brs = flags & kFlagBrs;
  f.extended = flags & kFlagExt;
  f.error = flags & kFlagErr;
  f.len = static_cast<std::uint8_t>(len);
  f.id = 0;
  for (int i = 0; i < 4; ++i) f.id |= static_cast<std::uint32_t>(buf[8 + i]) << (8 * i);
  if (!f.error && f.id > (f.extended ? 0x1FFFFFFFu : 0x7FFu)) return false;
  std::memcpy(f.data.data(), buf + kUdpCanHeader, len);
  out = f;
  return true;
}

UdpCanTransport::UdpCanTransport(const Options& o) : peer_port_(o.peer_port) {
  const std::string where = "udp-can " + o.host + ":" + std::to_string(o.local_port);
  in_addr addr{};
  if (inet_pton(AF_INET, o.host.c_str(), &addr) != 1) {
    throw std::system_error(EINVAL, std::generic_category(), where + ": host is not an IPv4 address");
  }
  addr_be_ = addr.s_addr;
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), where + ": socket");
  ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &o.rcvbuf_bytes, sizeof o.rcvbuf_bytes);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(o.local_port);
  sa.sin_addr = addr;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw std::system_error(e, std::generic_category(), where + ": bind");
  }
  socklen_t sl = sizeof sa;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&sa), &sl);
  local_port_ = ntohs(sa.sin_port);
  name_ = "udp:" + std::to_string(local_port_);
}

UdpCanTransport::~UdpCanTransport() {
  if (fd_ >= 0) ::close(fd_);
}

void UdpCanTransport::setPeerPort(std::uint16_t port) noexcept { peer_port_ = port; }

namespace {
bool sendDatagram(int fd, std::uint32_t addr_be, std::uint16_t port, const CanFrame& f, int& err) noexcept {
  std::uint8_t buf[kUdpCanHeader + kCanFdMaxPayload];
  const std::size_t n = encodeUdpCan(f, buf);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(port);
  sa.sin_addr.s_addr = addr_be;
  const ssize_t r = ::sendto(fd, buf, n, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&sa), sizeof sa);
  err = r < 0 ? errno : 0;
  return r == static_cast<ssize_t>(n);
}
}  // namespace

TxStatus UdpCanTransport::send(const CanFrame& frame) noexcept {
  if (state_ == BusState::kBusOff) {
    ++counters_.tx_bus_off;
    return TxStatus::kBusOff;
  }
  if (frame.fd ? !isValidFdLength(frame.len) : frame.len > kCanMaxPayload) {
    ++counters_.tx_errors;
    return TxStatus::kError;
  }
  int err = 0;
  if (!sendDatagram(fd_, addr_be_, peer_port_, frame, err)) {
    if (err == EAGAIN || err == EWOULDBLOCK || err == ENOBUFS) {
      ++counters_.tx_queue_full;
      return TxStatus::kQueueFull;
    }
    // ECONNREFUSED on loopback means the peer is not running yet: the frame is simply lost, as on
    // a CAN bus without a listener (it would not be acknowledged).
    ++counters_.tx_errors;
    return TxStatus::kError;
  }
  ++counters_.tx_frames;
  return TxStatus::kOk;
}

RxStatus UdpCanTransport::receive(CanFrame& out) noexcept {
  std::uint8_t buf[kUdpCanHeader + kCanFdMaxPayload + 1];
  for (;;) {
    const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return RxStatus::kEmpty;
      if (errno == EINTR) continue;
      if (errno == ECONNREFUSED) continue;  // ICMP from an earlier send to an absent peer
      ++counters_.rx_errors;
      return RxStatus::kError;
    }
    if (!decodeUdpCan(buf, static_cast<std::size_t>(n), out)) {
      ++counters_.rx_errors;
      return RxStatus::kError;
    }
    return acceptFrame(out);
  }
}

bool UdpCanTransport::sendErrorIndication(std::uint32_t mask) noexcept {
  CanFrame f;
  f.error = true;
  f.id = mask;
  int err = 0;
  return sendDatagram(fd_, addr_be_, peer_port_, f, err);
}

bool UdpCanTransport::restart() noexcept {
  ++counters_.restarts;
  state_ = BusState::kErrorActive;
  return sendErrorIndication(kErrorRestarted);
}

}  // namespace pmg::hal::bus
