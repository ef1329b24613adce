#include "pmg/hal/bus/transport.hpp"

#include <stdexcept>

#include "pmg/hal/bus/ethercat_bridge.hpp"

namespace pmg::hal::bus {

const char* toString(BusState s) noexcept {
  switch (s) {
    case BusState::kErrorActive: return "error-active";
    case BusState::kErrorPassive: return "error-passive";
    case BusState::kBusOff: return "bus-off";
  }
  return "unknown";
}

const char* toString(TxStatus s) noexcept {
  switch (s) {
    case TxStatus::kOk: return "ok";
    case TxStatus::kQueueFull: return "tx queue full";
    case TxStatus::kBusOff: return "bus-off";
    case TxStatus::kError: return "error";
  }
  return "unknown";
}

RxStatus CanTransport::acceptFrame(const CanFrame& frame) noexcept {
  if (frame.error) {
    applyErrorClass(frame.id);
  } else {
    ++counters_.rx_frames;
  }
  return RxStatus::kFrame;
}

void CanTransport::applyErrorClass(std::uint32_t mask) noexcept {
  ++counters_.rx_error_frames;
  if (mask & kErrorBusOff) {
    if (state_ != BusState::kBusOff) ++counters_.bus_off_events;
    state_ = BusState::kBusOff;
  } else if (mask & kErrorRestarted) {
    state_ = BusState::kErrorActive;
  } else if ((mask & kErrorPassive) && state_ != BusState::kBusOff) {
    state_ = BusState::kErrorPassive;
  }
}

// ---------------------------------------------------------------- EtherCAT seam
EthercatCanTransport::EthercatCanTransport(EthercatCanGateway& gateway, int channel, const std::string& name)
    : gw_(gateway), channel_(channel) {
  if (channel < 0 || channel >= gateway.channelCount()) {
    throw std::out_of_range(name + ": EtherCAT-CAN channel " + std::to_string(channel) + " not in [0, " +
                            std::to_string(gateway.channelCount()) + ")");
  }
  name_ = name;
  state_ = gw_.channelState(channel_);
}

TxStatus EthercatCanTransport::send(const CanFrame& frame) noexcept {
  state_ = gw_.channelState(channel_);
  if (state_ == BusState::kBusOff) {
    ++counters_.tx_bus_off;
    return TxStatus::kBusOff;
  }
  if (!gw_.queueTx(channel_, frame)) {
    ++counters_.tx_queue_full;
    return TxStatus::kQueueFull;
  }
  ++counters_.tx_frames;
  return TxStatus::kOk;
}

RxStatus EthercatCanTransport::receive(CanFrame& out) noexcept {
  const BusState before = state_;
  state_ = gw_.channelState(channel_);
  if (state_ == BusState::kBusOff && before != BusState::kBusOff) ++counters_.bus_off_events;
  if (!gw_.popRx(channel_, out)) return RxStatus::kEmpty;
  return acceptFrame(out);
}

bool EthercatCanTransport::restart() noexcept {
  ++counters_.restarts;
  return gw_.requestRestart(channel_);
}

}  // namespace pmg::hal::bus
