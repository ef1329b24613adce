// CanBackend against a scripted driver peer on UDP loopback: enable on the first cycle, joint/motor
// mapping, NaN commands never encoded, reply routing and checks, duplicates, late frames, missing
// motors, bus-off restart, IMU frames, status, and no allocation in exchange().
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <system_error>
#include <thread>

#include "g1_fixture.hpp"
#include "alloc_counter.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/hal/bus/can_backend.hpp"
#include "pmg/hal/bus/imu_protocol.hpp"
#include "pmg/hal/bus/mit_protocol.hpp"
#include "pmg/hal/realtime.hpp"
#include "pmg/hal/bus/sil_emulator.hpp"

using namespace pmg::hal::bus;

namespace {

BusPlan twoBusPlan() {
  std::vector<BusConfig> buses(2);
  for (int b = 0; b < 2; ++b) {
    buses[b].name = "can" + std::to_string(b);
    for (int k = 0; k < 2; ++k) {
      MotorSpec m;
      m.name = "j" + std::to_string(2 * b + k);
      m.joint_index = 2 * b + k;
      m.motor_id = static_cast<std::uint8_t>(k + 1);
      m.command_can_id = static_cast<std::uint32_t>(k + 1);
      m.reply_can_id = 0;
      m.reply_limits.q_min = -3.0;
      m.reply_limits.q_max = 3.0;
      buses[b].motors.push_back(m);
    }
  }
  buses[1].motors[1].direction = -1.0;  // joint 3 mounted reversed, with an offset
  buses[1].motors[1].offset = 0.5;
  BusPlanOptions o;
  o.num_joints = 4;
  return BusPlan(buses, o, "test plan");
}

// The driver side: replies to every frame per the current script, then sends the IMU frame.
class Peer {
 public:
  Peer(const BusPlan& plan, std::uint16_t base) : plan_(plan) {
    for (std::size_t b = 0; b <= 2; ++b) {
      UdpCanTransport::Options o;
      o.local_port = udpPorts(base, 2, b).second;
      o.peer_port = udpPorts(base, 2, b).first;
      (b < 2 ? buses_[b] : imu_) = std::make_unique<UdpCanTransport>(o);
    }
    thread_ = std::thread([this] { run(); });
  }
  ~Peer() {
    stop_ = true;
    thread_.join();
  }
  std::atomic<int> silent_joint{-1};
  std::atomic<bool> duplicate{false}, wrong_length{false}, send_imu{true};
  std::atomic<int> late_joint{-1};
  std::mutex mutex;
  std::vector<std::pair<int, CanFrame>> received;  // (joint, frame)
  std::vector<double> arrival;                     // CLOCK_MONOTONIC [s] per received frame
  UdpCanTransport& bus(int b) { return *buses_[b]; }

 private:
  // The IMU frame closes a cycle (the lockstep host waits for it): send it once all four motors
  // were addressed, or 20 ms after the cycle's first frame (a bus may be off).
  void run() {
    pollfd fds[2] = {{buses_[0]->pollFd(), POLLIN, 0}, {buses_[1]->pollFd(), POLLIN, 0}};
    int addressed = 0;
    auto first = std::chrono::steady_clock::now();
    while (!stop_) {
      ::poll(fds, 2, 1);
      bool any = false;
      for (int b = 0; b < 2; ++b) {
        CanFrame f;
        while (buses_[b]->receive(f) == RxStatus::kFrame) {
          if (f.error) continue;
          const MotorSpec& m = plan_.buses()[static_cast<std::size_t>(b)].motors[f.id - 1];
          {
            std::lock_guard<std::mutex> lock(mutex);
            received.emplace_back(m.joint_index, f);
            arrival.push_back(pmg::hal::rt::now());
          }
          any = true;
          if (addressed++ == 0) first = std::chrono::steady_clock::now();
          if (m.joint_index == silent_joint) continue;
          CanFrame r;
          MitProtocol::encodeReply(m, MotorFeedback{m.motor_id, 0.25 * (m.joint_index + 1), 1.0, -2.0}, r);
          if (wrong_length) r.len = 7;
          if (m.joint_index == late_joint) {
            held_ = r;
            held_bus_ = b;
            continue;
          }
          buses_[b]->send(r);
          if (duplicate) buses_[b]->send(r);
        }
      }
      (void)any;
      const bool timed_out = addressed > 0 && std::chrono::steady_clock::now() - first > std::chrono::milliseconds(20);
      if (addressed >= 4 || timed_out) {
        addressed = 0;
        if (held_bus_ >= 0 && late_joint < 0) {
          buses_[held_bus_]->send(held_);
          held_bus_ = -1;
        }
        if (send_imu) {
          pmg::ImuState s;
          s.quat_wxyz = {1.0, 0.0, 0.0, 0.0};
          s.gyro = {0.1, 0.2, 0.3};
          s.acc = {0.0, 0.0, 9.81};
          CanFrame f;
          encodeImu(s, seq_++, f);
          imu_->send(f);
        }
      }
    }
  }
  BusPlan plan_;
  std::unique_ptr<UdpCanTransport> buses_[2], imu_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  CanFrame held_;
  int held_bus_ = -1;
  std::uint32_t seq_ = 0;
};

struct Rig {
  BusPlan plan = twoBusPlan();
  std::unique_ptr<Peer> peer_ptr;
  std::unique_ptr<CanBackend> can;
  pmg::LowCommand cmd;
  pmg::LowState st;
  bool paced_;
  Peer& peer;
  explicit Rig(bool paced = false) : paced_(paced), peer(bind()) {}
  // A port block per process; on a collision (ctest runs tests in parallel) move on.
  Peer& bind() {
    std::unique_ptr<CanTransport> imu;
    std::vector<std::unique_ptr<CanTransport>> ts;
    for (int attempt = 0;; ++attempt) {
      const auto base = static_cast<std::uint16_t>(32000 + ((getpid() + 53 * attempt) % 1000) * 8);
      try {
        ts = makeHostUdpTransports(plan, base, imu);
        peer_ptr = std::make_unique<Peer>(plan, base);
        break;
      } catch (const std::system_error&) {
        if (attempt >= 20) throw;
      }
    }
    CanBackendOptions o;
    o.lockstep = true;
    o.lockstep_timeout_s = 0.2;
    o.bus_off_restart_cycles = 3;
    if (paced_) {
      o.paced = true;
      o.lockstep = false;  // real-time reply window
    }
    can = std::make_unique<CanBackend>(plan, std::move(ts), std::move(imu), o);
    cmd.num_motors = 4;
    return *peer_ptr;
  }
  std::vector<std::pair<int, CanFrame>> takeReceived() {
    std::lock_guard<std::mutex> lock(peer.mutex);
    auto r = std::move(peer.received);
    peer.received.clear();
    return r;
  }
};

}  // namespace

TEST(CanBackend, EnablesFirstThenSendsMappedCommands) {
  Rig r;
  EXPECT_EQ(r.can->exchange(r.cmd, r.st), pmg::BackendStatus::kOk);
  auto first = r.takeReceived();
  ASSERT_EQ(first.size(), 4u);
  for (auto& [j, f] : first) {
    ControlRequest req{};
    EXPECT_TRUE(MitProtocol::decodeControl(f, req)) << "joint " << j;
    EXPECT_EQ(req, ControlRequest::kEnable);
  }
  r.cmd.motors[3] = pmg::MotorCommand{0.2, 1.0, 30.0, 1.0, 2.0};
  r.cmd.motors[1] = pmg::MotorCommand{-0.3, 0.0, 20.0, 0.5, 0.0};
  EXPECT_EQ(r.can->exchange(r.cmd, r.st), pmg::BackendStatus::kOk);
  for (auto& [j, f] : r.takeReceived()) {
    const MotorSpec& m = r.plan.buses()[static_cast<std::size_t>(j / 2)].motors[static_cast<std::size_t>(j % 2)];
    MotorCommand mc;
    ASSERT_TRUE(MitProtocol::decodeCommand(m, f, mc));
    if (j == 3) {  // direction -1, offset 0.5: motor q = -0.2 + 0.5
      EXPECT_NEAR(mc.q, 0.3, 1e-3);
      EXPECT_NEAR(mc.qd, -1.0, 0.05);
      EXPECT_NEAR(mc.tau_ff, -2.0, 0.01);
      EXPECT_NEAR(mc.kp, 30.0, 0.2);
    }
    if (j == 1) {
      EXPECT_NEAR(mc.q, -0.3, 1e-3);
    }
  }
  // Replies decoded to joint side: joint 3 reports motor q 1.0 -> joint q = -(1.0 - 0.5).
  EXPECT_TRUE(r.st.motors[3].valid);
  EXPECT_NEAR(r.st.motors[3].q, -0.5, 1e-3);
  EXPECT_NEAR(r.st.motors[3].qd, -1.0, 0.05);
  EXPECT_NEAR(r.st.motors[0].q, 0.25, 1e-3);
  EXPECT_TRUE(r.st.imu.valid);
  EXPECT_NEAR(r.st.imu.gyro[2], 0.3, 1e-6);
  EXPECT_EQ(r.st.sequence, 2u);
  EXPECT_NEAR(r.st.time, 0.004, 1e-12);
}

TEST(CanBackend, NonFiniteCommandIsNeverEncoded) {
  Rig r;
  r.can->exchange(r.cmd, r.st);
  r.takeReceived();
  r.cmd.motors[2] = pmg::MotorCommand{std::nan(""), 0.0, 100.0, 2.0, 5.0};
  r.can->exchange(r.cmd, r.st);
  EXPECT_EQ(r.can->nonfiniteCommands(), 1u);
  for (auto& [j, f] : r.takeReceived()) {
    if (j != 2) continue;
    MotorCommand mc;
    ASSERT_TRUE(MitProtocol::decodeCommand(r.plan.buses()[1].motors[0], f, mc));
    EXPECT_NEAR(mc.kp, 0.0, 1e-9);
    EXPECT_NEAR(mc.kd, 0.0, 1e-9);
    EXPECT_NEAR(mc.tau_ff, 0.0, 0.01) << "zero torque instead";
  }
}

TEST(CanBackend, MissingDuplicateAndRejectedRepliesAreCounted) {
  Rig r;
  r.can->exchange(r.cmd, r.st);
  r.peer.silent_joint = 2;
  EXPECT_EQ(r.can->exchange(r.cmd, r.st), pmg::BackendStatus::kPartial);
  EXPECT_FALSE(r.st.motors[2].valid);
  EXPECT_TRUE(r.st.motors[1].valid);
  EXPECT_EQ(r.can->motorCounters(2).missing, 1u);
  r.peer.silent_joint = -1;
  r.peer.duplicate = true;
  EXPECT_EQ(r.can->exchange(r.cmd, r.st), pmg::BackendStatus::kOk);
  r.peer.duplicate = false;
  r.can->exchange(r.cmd, r.st);  // duplicates may land in this cycle's late drain or the previous one
  EXPECT_GE(r.can->motorCounters(0).duplicates + r.can->motorCounters(0).late, 1u);
  r.peer.wrong_length = true;
  EXPECT_EQ(r.can->exchange(r.cmd, r.st), pmg::BackendStatus::kFault);
  EXPECT_GE(r.can->motorCounters(1).rejected, 1u);
  r.peer.wrong_length = false;
  EXPECT_EQ(r.can->exchange(r.cmd, r.st), pmg::BackendStatus::kOk);
}

TEST(CanBackend, LateReplyOfThePreviousCycleIsNotUsed) {
  Rig r;
  r.can->exchange(r.cmd, r.st);
  r.peer.late_joint = 1;
  r.can->exchange(r.cmd, r.st);
  EXPECT_FALSE(r.st.motors[1].valid);
  r.peer.late_joint = -1;  // the held reply goes out after the next cycle's replies
  r.can->exchange(r.cmd, r.st);
  r.can->exchange(r.cmd, r.st);
  EXPECT_GE(r.can->motorCounters(1).late + r.can->motorCounters(1).duplicates, 1u);
  EXPECT_TRUE(r.st.motors[1].valid);
}

TEST(CanBackend, BusOffSkipsTheBusAndRestartsIt) {
  Rig r;
  r.can->exchange(r.cmd, r.st);
  ASSERT_TRUE(r.peer.bus(1).sendErrorIndication(kErrorBusOff));
  r.can->exchange(r.cmd, r.st);  // the indication arrives (drained or in the reply loop)
  r.can->exchange(r.cmd, r.st);
  EXPECT_EQ(r.can->transport(1).counters().bus_off_events, 1u);
  EXPECT_FALSE(r.st.motors[2].valid);
  EXPECT_TRUE(r.st.motors[0].valid) << "the other bus keeps working";
  for (int i = 0; i < 4; ++i) r.can->exchange(r.cmd, r.st);
  EXPECT_EQ(r.can->transport(1).counters().restarts, 1u);
  EXPECT_EQ(r.can->transport(1).state(), BusState::kErrorActive);
  r.can->exchange(r.cmd, r.st);
  EXPECT_TRUE(r.st.motors[2].valid) << "replies resume after the restart";
}

TEST(CanBackend, PacedSendsFollowTheSlotSchedule) {
  Rig r(/*paced=*/true);
  r.can->exchange(r.cmd, r.st);
  // Let every frame of the first cycle (enable + command) arrive before clearing: on a loaded
  // machine they can reach the peer after exchange() returned.
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  {
    std::lock_guard<std::mutex> lock(r.peer.mutex);
    r.peer.received.clear();
    r.peer.arrival.clear();
  }
  r.can->exchange(r.cmd, r.st);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::lock_guard<std::mutex> lock(r.peer.mutex);
  ASSERT_EQ(r.peer.received.size(), 4u);
  // Slot order: both buses' first motors, then both second motors (offset = per-motor round).
  const double per_motor = r.plan.loads()[0].per_motor_s;
  double first[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < 4; ++i) first[r.peer.received[i].first] = r.peer.arrival[i];
  EXPECT_TRUE(r.peer.received[0].first == 0 || r.peer.received[0].first == 2);
  EXPECT_TRUE(r.peer.received[3].first == 1 || r.peer.received[3].first == 3);
  // The spacing itself (>= one per-motor round between a bus's frames) is a timing property: the
  // receiver thread's arrival stamps are unreliable on a loaded CI machine, so pmg_bench_hal
  // measures it instead of this test. Here: every second-round frame arrives after its bus's first.
  EXPECT_GE(first[1], first[0]);
  EXPECT_GE(first[3], first[2]);
  (void)per_motor;
}

TEST(CanBackend, ExchangeDoesNotAllocate) {
  Rig r;
  r.can->exchange(r.cmd, r.st);
  long allocs = 0;
  {
    pmg::test::AllocationGuard scope;
    for (int i = 0; i < 50; ++i) r.can->exchange(r.cmd, r.st);
    allocs = static_cast<long>(scope.count());
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_EQ(r.can->motorCounters(0).replies, 51u);
}

TEST(CanBackend, SetupErrors) {
  BusPlan plan = twoBusPlan();
  std::vector<std::unique_ptr<CanTransport>> one;
  one.push_back(std::make_unique<UdpCanTransport>(UdpCanTransport::Options{}));
  EXPECT_THROW(CanBackend(plan, std::move(one), nullptr), std::invalid_argument);
  CanBackendSetup s;
  s.plan_file = pmg::test::g1CanPlanPath();
  s.transport = "carrier-pigeon";
  EXPECT_THROW(makeCanBackend(s), std::runtime_error);
}

// makeCanBackend checks the plan against the robot config (the source of truth for bus/motor ids)
// before it opens any transport: a mismatch names both files, the joint and both ids.
TEST(CanBackend, SetupRefusesAPlanThatDisagreesWithTheRobotConfig) {
  pmg::RobotConfig robot = pmg::test::g1Robot();
  robot.joints[9].motor_id = 12;  // right knee: can1 motor 4 in config/hal/g1_can.yaml
  CanBackendSetup s;
  s.plan_file = pmg::test::g1CanPlanPath();
  s.robot = &robot;
  s.transport = "carrier-pigeon";  // never reached
  try {
    makeCanBackend(s);
    FAIL() << "mismatch accepted";
  } catch (const pmg::ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(s.plan_file), std::string::npos) << msg;
    EXPECT_NE(msg.find(robot.source_file), std::string::npos) << msg;
    EXPECT_NE(msg.find("joint 'right_knee_joint' is on bus can1 with motor_id 4"), std::string::npos) << msg;
    EXPECT_NE(msg.find("says bus can1 with motor_id 12"), std::string::npos) << msg;
  }
}

TEST(ImuFrame, RoundTripAndRejects) {
  pmg::ImuState s;
  s.quat_wxyz = {0.9, 0.1, -0.3, 0.2};
  s.gyro = {1.5, -2.0, 0.25};
  s.acc = {0.5, -0.5, 9.8};
  CanFrame f;
  encodeImu(s, 77, f);
  EXPECT_TRUE(f.fd);
  EXPECT_EQ(f.len, 48);
  pmg::ImuState out;
  std::uint32_t seq = 0;
  ASSERT_TRUE(decodeImu(f, out, seq));
  EXPECT_EQ(seq, 77u);
  EXPECT_TRUE(out.valid);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(out.quat_wxyz[i], s.quat_wxyz[i], 1e-6);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(out.gyro[i], s.gyro[i], 1e-6);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(out.acc[i], s.acc[i], 1e-5);
  CanFrame bad = f;
  bad.id = 0x0F1;
  EXPECT_FALSE(decodeImu(bad, out, seq));
  bad = f;
  bad.len = 32;
  EXPECT_FALSE(decodeImu(bad, out, seq));
  bad = f;
  bad.fd = false;
  EXPECT_FALSE(decodeImu(bad, out, seq));
  s.gyro[1] = std::nan("");
  encodeImu(s, 78, bad);
  EXPECT_FALSE(decodeImu(bad, out, seq)) << "NaN gyro";
}
