#include "pmg/hal/bus/can_backend.hpp"

#include <poll.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pmg/hal/bus/imu_protocol.hpp"
#include "pmg/hal/realtime.hpp"
#include "pmg/hal/bus/sil_emulator.hpp"
#include "pmg/hal/bus/socketcan_transport.hpp"

namespace pmg::hal::bus {

std::string CanBackendOptions::validate() const {
  if (!(reply_window_s >= 0.0)) return "reply_window_s: expected >= 0 s";
  if (!(lockstep_timeout_s > 0.0)) return "lockstep_timeout_s: expected > 0 s";
  if (!(lockstep_imu_grace_s >= 0.0)) return "lockstep_imu_grace_s: expected >= 0 s";
  if (bus_off_restart_cycles < 1) return "bus_off_restart_cycles: expected >= 1";
  return {};
}

CanBackend::CanBackend(BusPlan plan, std::vector<std::unique_ptr<CanTransport>> transports,
                       std::unique_ptr<CanTransport> imu, CanBackendOptions options)
    : plan_(std::move(plan)), opt_(options), transports_(std::move(transports)), imu_(std::move(imu)) {
  const std::string msg = opt_.validate();
  if (!msg.empty()) throw std::invalid_argument("can backend options: " + msg);
  const std::size_t nb = plan_.buses().size();
  if (transports_.size() != nb)
    throw std::invalid_argument("can backend: " + std::to_string(transports_.size()) + " transports for " +
                                std::to_string(nb) + " buses");
  num_joints_ = plan_.options().num_joints;
  if (num_joints_ > pmg::kMaxMotors)
    throw std::invalid_argument("can backend: " + std::to_string(num_joints_) + " joints > kMaxMotors");
  route_.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    if (!transports_[b]) throw std::invalid_argument("can backend: transport " + std::to_string(b) + " is null");
    protocols_.push_back(makeMotorProtocol(plan_.buses()[b].protocol));
    route_[b].fill(-1);
    const auto& motors = plan_.buses()[b].motors;
    for (std::size_t k = 0; k < motors.size(); ++k) route_[b][motors[k].motor_id] = static_cast<std::int16_t>(k);
    pollfds_.push_back(::pollfd{transports_[b]->pollFd(), POLLIN, 0});
  }
  if (imu_) pollfds_.push_back(::pollfd{imu_->pollFd(), POLLIN, 0});
  // Send events of one slot: queued mode keeps plan order bus by bus; paced mode sorts by offset.
  for (std::size_t b = 0; b < nb; ++b) {
    for (const SlotEntry& e : plan_.schedule()[b])
      events_.push_back(SendEvent{e.send_offset_s, b, static_cast<std::size_t>(e.motor)});
  }
  if (opt_.paced) {
    std::stable_sort(events_.begin(), events_.end(),
                     [](const SendEvent& a, const SendEvent& c) { return a.offset_s < c.offset_s; });
  }
  skip_bus_.assign(nb, 0);
  motor_counters_.resize(static_cast<std::size_t>(num_joints_));
  got_.assign(static_cast<std::size_t>(num_joints_), 0);
  enabled_.assign(static_cast<std::size_t>(num_joints_), 0);
  bus_off_cycles_.assign(nb, 0);
  double busiest = 0.0;
  for (const BusLoad& l : plan_.loads()) busiest = std::max(busiest, l.busy_s);
  window_s_ = opt_.reply_window_s > 0.0 ? opt_.reply_window_s
                                        : std::min(busiest + 0.2e-3, 0.9 * plan_.options().period_s);
}

CanBackend::~CanBackend() {
  // Best effort: leave every motor disabled (zero torque).
  for (std::size_t b = 0; b < transports_.size(); ++b) {
    for (const MotorSpec& m : plan_.buses()[b].motors) {
      CanFrame f;
      protocols_[b]->encodeControl(m, ControlRequest::kDisable, f);
      transports_[b]->send(f);
    }
  }
}

std::string CanBackend::report() const {
  std::string out;
  const auto line = [&](const std::string& l) { out += (out.empty() ? "" : "\n") + l; };
  int silent_total = 0, total = 0;
  for (const BusConfig& bus : plan_.buses()) {
    std::string silent, lossy;
    for (const MotorSpec& m : bus.motors) {
      ++total;
      const MotorLinkCounters& c = motor_counters_[static_cast<std::size_t>(m.joint_index)];
      if (c.replies == 0) {
        silent += (silent.empty() ? "" : ", ") + m.name;
        ++silent_total;
      } else if (c.missing > 0 || c.rejected > 0) {
        lossy += (lossy.empty() ? "" : ", ") + m.name + " (" + std::to_string(c.missing) + " missing, " +
                 std::to_string(c.rejected) + " rejected)";
      }
    }
    if (!silent.empty()) line("bus " + bus.name + ": no reply at all from " + silent);
    const std::size_t b = static_cast<std::size_t>(&bus - plan_.buses().data());
    const TransportCounters& t = transports_[b]->counters();
    if (t.rx_error_frames > 0 || t.bus_off_events > 0 || t.tx_errors > 0 || t.tx_queue_full > 0 || t.rx_errors > 0)
      line("bus " + bus.name + ": " + std::to_string(t.rx_error_frames) + " error frames, " +
           std::to_string(t.bus_off_events) + " bus-off events, " + std::to_string(t.tx_errors + t.tx_bus_off) +
           " failed sends, " + std::to_string(t.tx_queue_full) + " full transmit queues, " +
           std::to_string(t.rx_errors) + " bad reads");
    if (!lossy.empty()) line("bus " + bus.name + ": " + lossy);
  }
  if (cycles_ > 0 && silent_total == total)
    line("no motor replied in " + std::to_string(cycles_) +
         " cycles: is the bus up (SocketCAN interfaces) or pmg_sil running on the configured port?");
  if (unroutable_ > 0) line(std::to_string(unroutable_) + " frames with an id no motor of the plan uses (wrong bus plan?)");
  if (imu_rejected_ > 0) line(std::to_string(imu_rejected_) + " IMU frames rejected");
  if (cycles_ > 0 && imu_frames_ == 0) line("no IMU frame received");
  return out;
}

bool CanBackend::allReplied() const noexcept {
  for (std::size_t b = 0; b < transports_.size(); ++b) {
    if (transports_[b]->state() == BusState::kBusOff) continue;  // nothing will come
    for (const MotorSpec& m : plan_.buses()[b].motors)
      if (!got_[static_cast<std::size_t>(m.joint_index)]) return false;
  }
  return true;
}

void CanBackend::handleFrame(std::size_t b, const CanFrame& f, pmg::LowState& state, bool late) noexcept {
  if (f.error) return;  // state already updated by the transport
  const MotorProtocol& p = *protocols_[b];
  const int id = p.replyMotorId(f);
  const int k = (id >= 0 && id < 256) ? route_[b][static_cast<std::size_t>(id)] : -1;
  if (k < 0) {
    ++unroutable_;
    return;
  }
  const MotorSpec& m = plan_.buses()[b].motors[static_cast<std::size_t>(k)];
  MotorLinkCounters& c = motor_counters_[static_cast<std::size_t>(m.joint_index)];
  // Any frame from the driver answers an enable request (it is only sent until the first answer):
  // the driver is in motor mode from then on.
  enabled_[static_cast<std::size_t>(m.joint_index)] = 1;
  if (late) {
    ++c.late;
    return;
  }
  MotorFeedback fb;
  if (p.decodeReply(m, f, fb) != ReplyStatus::kOk) {
    ++c.rejected;
    return;
  }
  std::uint8_t& got = got_[static_cast<std::size_t>(m.joint_index)];
  if (got) {
    ++c.duplicates;
    return;
  }
  got = 1;
  const MotorFeedback j = toJointSide(m, fb);
  pmg::MotorState& s = state.motors[static_cast<std::size_t>(m.joint_index)];
  s.q = j.q;
  s.qd = j.qd;
  s.tau = j.tau;
  s.valid = true;
  ++c.replies;
}

pmg::BackendStatus CanBackend::exchange(const pmg::LowCommand& command, pmg::LowState& state) noexcept {
  const std::size_t nb = transports_.size();
  CanFrame f;
  // 1. Late frames from the previous cycle.
  for (std::size_t b = 0; b < nb; ++b) {
    while (transports_[b]->receive(f) != RxStatus::kEmpty) handleFrame(b, f, state, true);
  }
  std::fill(got_.begin(), got_.end(), 0);
  imu_got_ = false;
  state.num_motors = num_joints_;
  for (int j = 0; j < num_joints_; ++j) state.motors[static_cast<std::size_t>(j)].valid = false;
  state.imu.valid = false;

  // 2. Sends: bus-off handling, then every motor's frame, either queued at once (bus by bus in plan
  //    order) or paced at its slot offset from the plan's schedule.
  const double t0 = rt::now();
  for (std::size_t b = 0; b < nb; ++b) {
    CanTransport& t = *transports_[b];
    if (t.state() == BusState::kBusOff) {
      if (++bus_off_cycles_[b] >= opt_.bus_off_restart_cycles) {
        t.restart();
        bus_off_cycles_[b] = 0;
      }
      skip_bus_[b] = 1;
      continue;
    }
    skip_bus_[b] = 0;
    bus_off_cycles_[b] = 0;
  }
  for (const SendEvent& e : events_) {
    if (skip_bus_[e.bus]) continue;
    if (opt_.paced) {
      // Until the send time, keep collecting replies (of the motors served before on any bus).
      for (double now = rt::now(); now < t0 + e.offset_s; now = rt::now()) {
        for (std::size_t b = 0; b < nb; ++b)
          while (transports_[b]->receive(f) == RxStatus::kFrame) handleFrame(b, f, state, false);
        const double wait = std::min(t0 + e.offset_s - now, 1e-3);
        const timespec ts{0, static_cast<long>(wait * 1e9)};
        ::ppoll(pollfds_.data(), transports_.size(), &ts, nullptr);
      }
    }
    const MotorProtocol& p = *protocols_[e.bus];
    const MotorSpec& m = plan_.buses()[e.bus].motors[e.motor];
    if (!enabled_[static_cast<std::size_t>(m.joint_index)]) {
      // Until the driver answers, ask it to enter motor mode again every cycle: a lost enable
      // (driver not powered yet, pmg_sil still starting) must not leave a limp motor that the
      // supervisor believes is holding its target.
      p.encodeControl(m, ControlRequest::kEnable, f);
    } else {
      const pmg::MotorCommand& jc = command.motors[static_cast<std::size_t>(m.joint_index)];
      const MotorCommand mc = toMotorSide(m, MotorCommand{jc.q, jc.qd, jc.kp, jc.kd, jc.tau_ff});
      if (!p.encodeCommand(m, mc, f)) {
        ++nonfinite_commands_;
        p.encodeCommand(m, MotorCommand{m.offset, 0.0, 0.0, 0.0, 0.0}, f);
      }
    }
    transports_[e.bus]->send(f);
  }

  // 3. Replies.
  const double deadline = t0 + (opt_.lockstep ? opt_.lockstep_timeout_s : window_s_);
  double motors_done_at = -1.0;
  for (;;) {
    for (std::size_t b = 0; b < nb; ++b) {
      while (transports_[b]->receive(f) == RxStatus::kFrame) handleFrame(b, f, state, false);
    }
    if (imu_) {
      while (imu_->receive(f) == RxStatus::kFrame) {
        std::uint32_t seq = 0;
        if (decodeImu(f, state.imu, seq)) {
          imu_got_ = true;
          ++imu_frames_;
        } else if (!f.error) {
          ++imu_rejected_;
        }
      }
    }
    const bool motors_done = allReplied();
    if (opt_.lockstep && motors_done && imu_ && !imu_got_ && motors_done_at < 0.0) {
      // Every reply is in; the IMU frame follows at once unless the IMU is silent: wait briefly.
      motors_done_at = rt::now();
    }
    const bool imu_overdue = motors_done_at >= 0.0 && rt::now() - motors_done_at > opt_.lockstep_imu_grace_s;
    if (opt_.lockstep ? (imu_ ? (imu_got_ || imu_overdue) : motors_done) : motors_done) {
      // In lockstep the SIL sends the IMU frame after all its replies: once it is here, every reply
      // that will come this cycle is already in the socket buffers; drain them once more.
      if (opt_.lockstep) {
        for (std::size_t b = 0; b < nb; ++b)
          while (transports_[b]->receive(f) == RxStatus::kFrame) handleFrame(b, f, state, false);
      }
      break;
    }
    const double now = rt::now();
    if (now >= deadline) break;
    const double wait = std::min(deadline - now, 1e-3);
    const timespec ts{0, static_cast<long>(wait * 1e9)};
    ::ppoll(pollfds_.data(), pollfds_.size(), &ts, nullptr);
  }

  int valid = 0;
  for (int j = 0; j < num_joints_; ++j) {
    if (got_[static_cast<std::size_t>(j)]) ++valid;
    else ++motor_counters_[static_cast<std::size_t>(j)].missing;
  }
  ++cycles_;
  state.sequence = cycles_;
  state.time = static_cast<double>(cycles_) * plan_.options().period_s;
  std::uint32_t faults = 0;
  for (std::size_t b = 0; b < nb; ++b) {
    const TransportCounters& c = transports_[b]->counters();
    faults += static_cast<std::uint32_t>(c.bus_off_events + c.tx_errors + c.rx_errors);
  }
  state.backend_faults = faults;
  if (valid == num_joints_) return pmg::BackendStatus::kOk;
  return valid > 0 ? pmg::BackendStatus::kPartial : pmg::BackendStatus::kFault;
}

std::unique_ptr<CanBackend> makeCanBackend(const CanBackendSetup& setup) {
  BusPlan plan = BusPlan::fromYaml(setup.plan_file);
  if (setup.robot) checkPlanAgainstRobot(plan.buses(), setup.plan_file, *setup.robot);
  CanBackendOptions o;
  o.lockstep = setup.lockstep;
  o.paced = setup.paced;
  std::unique_ptr<CanTransport> imu;
  std::vector<std::unique_ptr<CanTransport>> transports;
  if (setup.transport == "udp") {
    transports = makeHostUdpTransports(plan, setup.udp_base_port, imu);
  } else if (setup.transport == "socketcan") {
    for (const BusConfig& b : plan.buses()) transports.push_back(std::make_unique<SocketCanTransport>(b.name, b.timing.fd));
  } else {
    throw std::runtime_error("can backend: transport '" + setup.transport + "' unknown (expected udp or socketcan)");
  }
  return std::make_unique<CanBackend>(std::move(plan), std::move(transports), std::move(imu), o);
}

}  // namespace pmg::hal::bus
