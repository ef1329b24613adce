#include "pmg/hal/bus/sil_emulator.hpp"

#include <poll.h>

#include <cmath>
#include <stdexcept>

#include "pmg/hal/bus/imu_protocol.hpp"
#include "pmg/hal/bus/mit_protocol.hpp"
#include "pmg/hal/realtime.hpp"

namespace pmg::hal::bus {

SilDriverEmulator::SilDriverEmulator(const BusPlan& plan, std::unique_ptr<pmg::HalBackend> sim, std::uint16_t base)
    : plan_(plan), sim_(std::move(sim)) {
  if (!sim_) throw std::invalid_argument("SIL: simulation backend is null");
  if (std::fabs(sim_->cyclePeriod() - plan_.options().period_s) > 1e-9)
    throw std::invalid_argument("SIL: simulation cycle period differs from the bus plan's period_s");
  for (const BusConfig& b : plan_.buses()) {
    if (b.protocol != "mit")
      throw std::invalid_argument("SIL: bus '" + b.name + "' uses protocol '" + b.protocol +
                                  "'; the driver emulator speaks 'mit'");
  }
  buses_ = makeUdpTransports(plan_, base, UdpSide::kSil, imu_);
  const std::size_t nb = buses_.size();
  for (auto& t : buses_) fds_.push_back(::pollfd{t->pollFd(), POLLIN, 0});
  late_.reserve(64);
  route_.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    route_[b].assign(0x800, -1);
    const auto& motors = plan_.buses()[b].motors;
    for (std::size_t k = 0; k < motors.size(); ++k) route_[b][motors[k].command_can_id] = static_cast<std::int16_t>(k);
  }
  const auto nj = static_cast<std::size_t>(plan_.options().num_joints);
  addressed_.assign(nj, 0);
  enabled_.assign(nj, 0);
  bus_off_.assign(nb, 0);
  bus_off_done_.assign(nb, 0);
  cmd_.num_motors = static_cast<int>(nj);
  // Initial measurement: one step with zero torque so replies carry a real state from cycle 0.
  sim_->exchange(cmd_, state_);
}

void SilDriverEmulator::setFaults(const SilFaults& f) {
  std::lock_guard<std::mutex> lock(faults_mutex_);
  pending_faults_ = f;
  faults_changed_ = true;
}

void SilDriverEmulator::post(std::function<void(pmg::HalBackend&)> action) {
  std::lock_guard<std::mutex> lock(faults_mutex_);
  actions_.push_back(std::move(action));
  faults_changed_ = true;
}

void SilDriverEmulator::reply(std::size_t b, std::size_t k, const SilFaults& f) {
  const MotorSpec& m = plan_.buses()[b].motors[k];
  const auto j = static_cast<std::size_t>(m.joint_index);
  if (m.joint_index == f.silent_joint) {
    ++counters_.silenced;
    return;
  }
  const pmg::MotorState& s = state_.motors[j];
  // Joint side -> motor side.
  MotorFeedback fb;
  fb.q = m.direction * s.q + m.offset;
  fb.qd = m.direction * s.qd;
  fb.tau = m.direction * s.tau;
  CanFrame fr;
  MitProtocol::encodeReply(m, fb, fr);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  if (u(rng_) < f.drop_prob) {
    ++counters_.dropped;
    return;
  }
  if (u(rng_) < f.corrupt_prob) {
    ++counters_.corrupted;
    switch (rng_() % 3) {
      case 0: fr.data[0] = 0xEE; break;  // foreign motor id
      case 1: fr.len = 5; break;         // truncated
      default: fr.data[1] = fr.data[2] = 0xFF; break;  // position at full scale
    }
  }
  if (u(rng_) < f.late_prob) {
    ++counters_.late;
    late_.emplace_back(b, fr);
    return;
  }
  buses_[b]->send(fr);
  ++counters_.replies;
  if (u(rng_) < f.dup_prob) {
    ++counters_.duplicated;
    buses_[b]->send(fr);
  }
}

void SilDriverEmulator::beginCycle() {
  if (faults_changed_.exchange(false)) {
    std::lock_guard<std::mutex> lock(faults_mutex_);
    const bool reseed = pending_faults_.seed != faults_.seed;
    faults_ = pending_faults_;
    if (reseed || counters_.cycles == 0) rng_.seed(faults_.seed);
    for (auto& a : actions_) a(*sim_);
    actions_.clear();
  }
  const std::size_t nb = buses_.size();
  if (faults_.bus_off_bus >= 0 && static_cast<std::size_t>(faults_.bus_off_bus) < nb &&
      !bus_off_done_[static_cast<std::size_t>(faults_.bus_off_bus)]) {
    const auto b = static_cast<std::size_t>(faults_.bus_off_bus);
    bus_off_[b] = bus_off_done_[b] = 1;
    buses_[b]->sendErrorIndication(kErrorBusOff);
    ++counters_.bus_off_injected;
  }
  std::fill(addressed_.begin(), addressed_.end(), 0);
}

bool SilDriverEmulator::pollFrames(bool reply_now) {
  bool any = false;
  CanFrame fr;
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    while (buses_[b]->receive(fr) == RxStatus::kFrame) {
      if (fr.error) {
        if (fr.id & kErrorRestarted) {
          bus_off_[b] = 0;
          ++counters_.restarts_seen;
        }
        continue;
      }
      if (bus_off_[b]) continue;  // the emulated controller is off the bus
      // A frame no driver of this bus takes (extended or foreign id, wrong kind or length) is
      // dropped and counted, as a real bus would leave it unanswered.
      if (fr.extended || fr.id >= 0x800) {
        ++counters_.rejected;
        continue;
      }
      const int k = route_[b][fr.id];
      if (k < 0) {
        ++counters_.rejected;
        continue;
      }
      const MotorSpec& m = plan_.buses()[b].motors[static_cast<std::size_t>(k)];
      const auto j = static_cast<std::size_t>(m.joint_index);
      ControlRequest cr{};
      MotorCommand mc;
      if (MitProtocol::decodeControl(fr, cr)) {
        if (cr == ControlRequest::kEnable) enabled_[j] = 1;
        if (cr == ControlRequest::kDisable) enabled_[j] = 0;
        ++counters_.controls;
      } else if (MitProtocol::decodeCommand(m, fr, mc)) {
        pmg::MotorCommand& c = cmd_.motors[j];
        c.q = m.direction * (mc.q - m.offset);
        c.qd = m.direction * mc.qd;
        c.kp = mc.kp;
        c.kd = mc.kd;
        c.tau_ff = m.direction * mc.tau_ff;
        ++counters_.commands;
      } else {
        ++counters_.rejected;
        continue;
      }
      addressed_[j] = 1;
      any = true;
      if (reply_now) reply(b, static_cast<std::size_t>(k), faults_);
    }
  }
  return any;
}

void SilDriverEmulator::flushLate() {
  for (auto& [b, frame] : late_) {
    if (!bus_off_[b]) buses_[b]->send(frame);
  }
  late_.clear();
}

void SilDriverEmulator::sendImuAndStep() {
  const SilFaults& f = faults_;
  if (!f.imu_silent) {
    pmg::ImuState imu = state_.imu;
    if (f.imu_frozen) {
      if (!frozen_captured_) {
        frozen_imu_ = imu;
        frozen_captured_ = true;
      }
      imu = frozen_imu_;
    } else {
      frozen_captured_ = false;
    }
    const double noise = std::sqrt(sensor_noise_ * sensor_noise_ + f.imu_gyro_noise * f.imu_gyro_noise);
    if (noise > 0.0 && !f.imu_frozen) {
      std::normal_distribution<double> n(0.0, noise);
      for (double& g : imu.gyro) g += n(rng_);
    }
    CanFrame imu_frame;
    encodeImu(imu, imu_seq_++, imu_frame);
    imu_->send(imu_frame);
    ++counters_.imu_frames;
  }
  // Step with the held set-points; disabled drivers apply no torque.
  pmg::LowCommand applied = cmd_;
  for (std::size_t j = 0; j < enabled_.size(); ++j)
    if (!enabled_[j]) applied.motors[j] = pmg::MotorCommand{};
  sim_->exchange(applied, state_);
  ++counters_.cycles;
}

bool SilDriverEmulator::runCycle(double timeout_s, bool step_anyway) {
  beginCycle();
  const std::size_t nb = buses_.size();
  // 1. Collect this cycle's frames.
  const double deadline = rt::now() + timeout_s;
  bool any = false;
  for (;;) {
    any = pollFrames(false) || any;
    bool all = true;
    for (std::size_t b = 0; b < nb && all; ++b) {
      if (bus_off_[b]) continue;
      for (const MotorSpec& m : plan_.buses()[b].motors) all = all && addressed_[static_cast<std::size_t>(m.joint_index)];
    }
    if (all && any) break;
    const double now = rt::now();
    if (now >= deadline) break;
    const timespec ts{0, static_cast<long>(std::min(deadline - now, 1e-3) * 1e9)};
    ::ppoll(fds_.data(), fds_.size(), &ts, nullptr);
  }
  if (!any && !step_anyway) return false;

  // 2. Replies (late ones from the previous cycle first), measured before this step.
  flushLate();
  for (std::size_t b = 0; b < nb; ++b) {
    if (bus_off_[b]) continue;
    const auto& motors = plan_.buses()[b].motors;
    for (std::size_t k = 0; k < motors.size(); ++k)
      if (addressed_[static_cast<std::size_t>(motors[k].joint_index)]) reply(b, k, faults_);
  }
  // 3. IMU last, 4. step.
  sendImuAndStep();
  return true;
}

void SilDriverEmulator::runRealtimeCycle(double step_at) {
  beginCycle();
  flushLate();
  for (;;) {
    pollFrames(true);
    const double now = rt::now();
    if (now >= step_at) break;
    const timespec ts{0, static_cast<long>(std::min(step_at - now, 1e-3) * 1e9)};
    ::ppoll(fds_.data(), fds_.size(), &ts, nullptr);
  }
  sendImuAndStep();
}

}  // namespace pmg::hal::bus
