// CAN transports: UDP loopback (frames, malformed datagrams, bus-off + restart, no allocation),
// SocketCAN frame/error conversion and setup errors, and the EtherCAT-CAN seam.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <deque>
#include <system_error>
#include <thread>

#include "alloc_counter.hpp"
#include "pmg/hal/bus/ethercat_bridge.hpp"
#include "pmg/hal/bus/socketcan_transport.hpp"
#include "pmg/hal/bus/udp_transport.hpp"

using namespace pmg::hal::bus;

namespace {

struct Pair {
  UdpCanTransport a{UdpCanTransport::Options{}};
  UdpCanTransport b{UdpCanTransport::Options{}};
  Pair() {
    a.setPeerPort(b.localPort());
    b.setPeerPort(a.localPort());
  }
};

// Wait (bounded) until `t` has something to read; loopback delivery is immediate in practice.
RxStatus receiveWithin(CanTransport& t, CanFrame& out, int timeout_ms = 1000) {
  pollfd p{t.pollFd(), POLLIN, 0};
  ::poll(&p, 1, timeout_ms);
  return t.receive(out);
}

CanFrame frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  for (std::uint8_t b : bytes) f.data[f.len++] = b;
  return f;
}

}  // namespace

TEST(UdpCanTransport, CarriesClassicFdAndErrorFrames) {
  Pair p;
  CanFrame out;
  EXPECT_EQ(p.b.receive(out), RxStatus::kEmpty);

  const CanFrame c = frame(0x123, {1, 2, 3, 4, 5, 6, 7, 8});
  ASSERT_EQ(p.a.send(c), TxStatus::kOk);
  ASSERT_EQ(receiveWithin(p.b, out), RxStatus::kFrame);
  EXPECT_EQ(out.id, 0x123u);
  EXPECT_EQ(out.len, 8);
  EXPECT_FALSE(out.fd);
  EXPECT_EQ(std::memcmp(out.data.data(), c.data.data(), 8), 0);

  CanFrame fd;
  fd.id = 0x7FF;
  fd.fd = fd.brs = true;
  fd.len = 64;
  for (int i = 0; i < 64; ++i) fd.data[i] = static_cast<std::uint8_t>(i * 3);
  ASSERT_EQ(p.a.send(fd), TxStatus::kOk);
  ASSERT_EQ(receiveWithin(p.b, out), RxStatus::kFrame);
  EXPECT_TRUE(out.fd);
  EXPECT_TRUE(out.brs);
  EXPECT_EQ(out.len, 64);
  EXPECT_EQ(std::memcmp(out.data.data(), fd.data.data(), 64), 0);

  CanFrame bad = c;
  bad.len = 9;  // classic frame cannot carry 9 bytes
  EXPECT_EQ(p.a.send(bad), TxStatus::kError);
  EXPECT_EQ(p.a.counters().tx_frames, 2u);
  EXPECT_EQ(p.a.counters().tx_errors, 1u);
  EXPECT_EQ(p.b.counters().rx_frames, 2u);
}

TEST(UdpCanTransport, RejectsMalformedDatagrams) {
  std::uint8_t buf[kUdpCanHeader + 64];
  CanFrame f = frame(0x10, {9, 9});
  const std::size_t n = encodeUdpCan(f, buf);
  CanFrame out;
  ASSERT_TRUE(decodeUdpCan(buf, n, out));
  EXPECT_FALSE(decodeUdpCan(buf, n - 1, out)) << "truncated";
  EXPECT_FALSE(decodeUdpCan(buf, 5, out)) << "shorter than header";
  std::uint8_t m[sizeof buf];
  std::memcpy(m, buf, n);
  m[0] = 'X';
  EXPECT_FALSE(decodeUdpCan(m, n, out)) << "magic";
  std::memcpy(m, buf, n);
  m[3] = 0x80;
  EXPECT_FALSE(decodeUdpCan(m, n, out)) << "unknown flag";
  std::memcpy(m, buf, n);
  m[9] = 0x08;  // id 0x810 > 11 bit
  EXPECT_FALSE(decodeUdpCan(m, n, out)) << "id width";
  CanFrame fd;
  fd.fd = true;
  fd.len = 13;  // not a legal FD length
  const std::size_t nfd = encodeUdpCan(fd, buf);
  EXPECT_FALSE(decodeUdpCan(buf, nfd, out));

  // A malformed datagram arriving on the socket is dropped and counted.
  Pair p;
  CanFrame ok = frame(0x1, {1});
  std::uint8_t raw[kUdpCanHeader + 64];
  std::size_t rn = encodeUdpCan(ok, raw);
  raw[2] = 99;  // wrong version
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(p.b.localPort());
  sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::sendto(p.a.pollFd(), raw, rn, 0, reinterpret_cast<sockaddr*>(&sa), sizeof sa),
            static_cast<ssize_t>(rn));
  CanFrame got;
  EXPECT_EQ(receiveWithin(p.b, got), RxStatus::kError);
  EXPECT_EQ(p.b.counters().rx_errors, 1u);
  EXPECT_EQ(p.b.receive(got), RxStatus::kEmpty);
}

TEST(UdpCanTransport, BusOffStopsTrafficUntilRestart) {
  Pair p;
  ASSERT_TRUE(p.a.sendErrorIndication(kErrorBusOff));  // the SIL side injects bus-off
  CanFrame out;
  ASSERT_EQ(receiveWithin(p.b, out), RxStatus::kFrame);
  EXPECT_TRUE(out.error);
  EXPECT_EQ(out.id, static_cast<std::uint32_t>(kErrorBusOff));
  EXPECT_EQ(p.b.state(), BusState::kBusOff);
  EXPECT_EQ(p.b.counters().bus_off_events, 1u);
  EXPECT_EQ(p.b.send(frame(1, {0})), TxStatus::kBusOff);
  EXPECT_EQ(p.b.counters().tx_bus_off, 1u);
  // Error-passive does not leave bus-off.
  ASSERT_TRUE(p.a.sendErrorIndication(kErrorPassive));
  ASSERT_EQ(receiveWithin(p.b, out), RxStatus::kFrame);
  EXPECT_EQ(p.b.state(), BusState::kBusOff);

  ASSERT_TRUE(p.b.restart());
  EXPECT_EQ(p.b.state(), BusState::kErrorActive);
  ASSERT_EQ(receiveWithin(p.a, out), RxStatus::kFrame);
  EXPECT_TRUE(out.error);
  EXPECT_TRUE(out.id & kErrorRestarted) << "the peer learns about the restart";
  EXPECT_EQ(p.b.send(frame(1, {0})), TxStatus::kOk);
  EXPECT_EQ(p.b.counters().restarts, 1u);
}

TEST(UdpCanTransport, CyclicCallsDoNotAllocate) {
  Pair p;
  CanFrame f = frame(0x42, {1, 2, 3, 4, 5, 6});
  CanFrame out;
  long allocs = 0;
  {
    pmg::test::AllocationGuard scope;
    for (int i = 0; i < 100; ++i) {
      p.a.send(f);
      p.b.receive(out);
    }
    p.b.receive(out);
    p.b.state();
    allocs = static_cast<long>(scope.count());
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_GT(p.b.counters().rx_frames, 0u);
}

TEST(UdpCanTransport, SetupErrorsNameTheEndpoint) {
  UdpCanTransport::Options o;
  o.host = "not-an-ip";
  try {
    UdpCanTransport t(o);
    FAIL();
  } catch (const std::system_error& e) {
    EXPECT_NE(std::string(e.what()).find("not-an-ip"), std::string::npos);
  }
  UdpCanTransport first{UdpCanTransport::Options{}};
  UdpCanTransport::Options same;
  same.local_port = first.localPort();
  EXPECT_THROW(UdpCanTransport t(same), std::system_error);
}

TEST(SocketCan, FrameConversionRoundTrip) {
  CanFrame c = frame(0x7FF, {0xDE, 0xAD, 0xBE, 0xEF, 0, 1, 2, 3});
  canfd_frame lf;
  ASSERT_EQ(toLinux(c, false, lf), static_cast<std::size_t>(CAN_MTU));
  EXPECT_EQ(lf.can_id, 0x7FFu);
  CanFrame back;
  ASSERT_TRUE(fromLinux(lf, CAN_MTU, back));
  EXPECT_EQ(back.id, c.id);
  EXPECT_EQ(back.len, 8);
  EXPECT_FALSE(back.fd);
  EXPECT_EQ(std::memcmp(back.data.data(), c.data.data(), 8), 0);

  CanFrame ext = c;
  ext.extended = true;
  ext.id = 0x1ABCDEF0;
  ASSERT_EQ(toLinux(ext, false, lf), static_cast<std::size_t>(CAN_MTU));
  EXPECT_TRUE(lf.can_id & CAN_EFF_FLAG);
  ASSERT_TRUE(fromLinux(lf, CAN_MTU, back));
  EXPECT_TRUE(back.extended);
  EXPECT_EQ(back.id, 0x1ABCDEF0u);

  CanFrame fd;
  fd.id = 0x100;
  fd.fd = fd.brs = true;
  fd.len = 12;
  fd.data[11] = 0x5A;
  EXPECT_EQ(toLinux(fd, false, lf), 0u) << "FD frame on a classic socket";
  ASSERT_EQ(toLinux(fd, true, lf), static_cast<std::size_t>(CANFD_MTU));
  EXPECT_TRUE(lf.flags & CANFD_BRS);
  ASSERT_TRUE(fromLinux(lf, CANFD_MTU, back));
  EXPECT_TRUE(back.fd && back.brs);
  EXPECT_EQ(back.len, 12);
  EXPECT_EQ(back.data[11], 0x5A);

  CanFrame too_big = c;
  too_big.id = 0x800;
  EXPECT_EQ(toLinux(too_big, false, lf), 0u);
  EXPECT_FALSE(fromLinux(lf, 3, back)) << "short read";
}

TEST(SocketCan, ErrorFramesMapToStates) {
  can_frame e{};
  e.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  e.can_dlc = CAN_ERR_DLC;
  EXPECT_EQ(errorClassFromLinux(e), static_cast<std::uint32_t>(kErrorBusOff));
  e.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  e.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  EXPECT_EQ(errorClassFromLinux(e), static_cast<std::uint32_t>(kErrorPassive));
  e.data[1] = CAN_ERR_CRTL_RX_OVERFLOW;
  EXPECT_EQ(errorClassFromLinux(e), static_cast<std::uint32_t>(kErrorRxOverflow));
  e.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
  EXPECT_EQ(errorClassFromLinux(e), static_cast<std::uint32_t>(kErrorRestarted));
  e.can_id = CAN_ERR_FLAG | CAN_ERR_TX_TIMEOUT | CAN_ERR_PROT;
  EXPECT_EQ(errorClassFromLinux(e), static_cast<std::uint32_t>(kErrorTxTimeout | kErrorProtocol));

  // Through fromLinux, an error frame becomes CanFrame::error with the class mask.
  canfd_frame lf{};
  lf.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  lf.len = CAN_ERR_DLC;
  CanFrame out;
  ASSERT_TRUE(fromLinux(lf, CAN_MTU, out));
  EXPECT_TRUE(out.error);
  EXPECT_EQ(out.id, static_cast<std::uint32_t>(kErrorBusOff));

  EXPECT_EQ(txStatusFromErrno(ENOBUFS), TxStatus::kQueueFull);
  EXPECT_EQ(txStatusFromErrno(EAGAIN), TxStatus::kQueueFull);
  EXPECT_EQ(txStatusFromErrno(ENETDOWN), TxStatus::kBusOff);
  EXPECT_EQ(txStatusFromErrno(EINVAL), TxStatus::kError);
}

TEST(SocketCan, MissingInterfaceFailsWithItsName) {
  // This machine has no CAN kernel module: either socket(PF_CAN) or the interface lookup fails;
  // both messages name the interface.
  try {
    SocketCanTransport t("pmgnocan0", false);
    FAIL() << "opened a CAN interface that does not exist";
  } catch (const std::system_error& e) {
    EXPECT_NE(std::string(e.what()).find("pmgnocan0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SocketCanTransport("this-name-is-far-too-long", false), std::system_error);
}

namespace {
// An in-memory gateway with two channels, as a user's EtherCAT master wrapper would look.
class MemoryGateway final : public EthercatCanGateway {
 public:
  int channelCount() const noexcept override { return 2; }
  bool queueTx(int ch, const CanFrame& f) noexcept override {
    if (tx[ch].size() >= 4) return false;
    tx[ch].push_back(f);
    return true;
  }
  bool popRx(int ch, CanFrame& out) noexcept override {
    if (rx[ch].empty()) return false;
    out = rx[ch].front();
    rx[ch].pop_front();
    return true;
  }
  BusState channelState(int ch) const noexcept override { return state[ch]; }
  bool requestRestart(int ch) noexcept override {
    state[ch] = BusState::kErrorActive;
    return true;
  }
  bool exchange() noexcept override {
    for (int ch = 0; ch < 2; ++ch) {
      for (const CanFrame& f : tx[ch]) rx[1 - ch].push_back(f);  // channels wired together
      tx[ch].clear();
    }
    return true;
  }
  std::deque<CanFrame> tx[2], rx[2];
  BusState state[2] = {BusState::kErrorActive, BusState::kErrorActive};
};
}  // namespace

TEST(EthercatBridge, ChannelsBehaveAsTransports) {
  MemoryGateway gw;
  EthercatCanTransport c0(gw, 0, "ecat0"), c1(gw, 1, "ecat1");
  EXPECT_THROW(EthercatCanTransport(gw, 2, "ecat2"), std::out_of_range);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(c0.send(frame(static_cast<std::uint32_t>(i + 1), {1})), TxStatus::kOk);
  EXPECT_EQ(c0.send(frame(9, {1})), TxStatus::kQueueFull);
  CanFrame out;
  EXPECT_EQ(c1.receive(out), RxStatus::kEmpty) << "nothing arrives before the exchange";
  ASSERT_TRUE(gw.exchange());
  for (int i = 0; i < 4; ++i) {
    ASSERT_EQ(c1.receive(out), RxStatus::kFrame);
    EXPECT_EQ(out.id, static_cast<std::uint32_t>(i + 1));
  }
  EXPECT_EQ(c1.receive(out), RxStatus::kEmpty);
  gw.state[0] = BusState::kBusOff;
  EXPECT_EQ(c0.send(frame(1, {1})), TxStatus::kBusOff);
  EXPECT_EQ(c0.state(), BusState::kBusOff);
  EXPECT_TRUE(c0.restart());
  EXPECT_EQ(c0.send(frame(1, {1})), TxStatus::kOk);
  EXPECT_EQ(c0.counters().tx_queue_full, 1u);
  EXPECT_EQ(c0.counters().restarts, 1u);
}

TEST(AllocCounter, CountsThisThreadsAllocations) {
  // The "no allocation" tests rely on this counter: it must see an allocation on this thread and
  // none of another thread's.
  std::atomic<bool> go{false}, done{false};
  std::thread other([&] {
    while (!go) std::this_thread::yield();
    static std::unique_ptr<int> q;  // escapes: the allocation cannot be elided
    q = std::make_unique<int>(2);
    done = true;
  });
  long n = 0;
  {
    pmg::test::AllocationGuard scope;
    go = true;
    while (!done) std::this_thread::yield();
    static std::unique_ptr<int> p;  // escapes: the allocation cannot be elided
    p = std::make_unique<int>(1);
    n = static_cast<long>(scope.count());
  }
  other.join();
  EXPECT_EQ(n, 1);
}
