#pragma once
/// @file ethercat_bridge.hpp
/// @brief Seam for an EtherCAT-to-CAN gateway (the seed robot's bus): the user provides an
/// EthercatCanGateway built on their EtherCAT master (IgH EtherLab, SOEM, ...); pmg wraps each of
/// its CAN channels as a CanTransport, so the motor protocol, bus plan, watchdogs and HAL loop stay
/// the same. No EtherCAT master library is shipped or required by pmg (see docs/hal.md).
///
/// Per 2 ms HAL tick the caller does, in this order:
///   1. gateway.exchange()      -- one EtherCAT process-data cycle: the frames queued in the last
///                                 tick go out, frames the gateway received come in;
///   2. transport.receive(...)  -- per channel, drain replies of the previous exchange;
///   3. transport.send(...)     -- per channel, queue this tick's commands (next exchange).
/// So with EtherCAT the reply to a command arrives one HAL tick (2 ms) later; the motor watchdogs
/// must allow for it (MotorWatchdog timeout >= 2 periods).

#include "pmg/hal/bus/transport.hpp"

namespace pmg::hal::bus {

/// What a user must implement for their gateway. All methods are called from the HAL thread at
/// 500 Hz and must be noexcept, non-blocking and allocation-free.
class EthercatCanGateway {
 public:
  virtual ~EthercatCanGateway() = default;
  /// Number of CAN channels behind the gateway (fixed after setup).
  virtual int channelCount() const noexcept = 0;
  /// Copy one frame into the channel's transmit mailbox of the next output process image.
  /// Returns false when the mailbox is full for this cycle.
  virtual bool queueTx(int channel, const CanFrame& frame) noexcept = 0;
  /// Pop one frame received on `channel` during the last exchange; false when none is left.
  virtual bool popRx(int channel, CanFrame& out) noexcept = 0;
  /// Fault confinement state of the channel's CAN controller (from the gateway's status PDO).
  virtual BusState channelState(int channel) const noexcept = 0;
  /// Ask the gateway to restart the channel's controller after bus-off (control word in the PDO).
  virtual bool requestRestart(int channel) noexcept = 0;
  /// One process-data exchange (send outputs, receive inputs). Returns false on a working-counter
  /// mismatch or lost frame, in which case no rx frames are available this cycle.
  virtual bool exchange() noexcept = 0;
};

/// One CAN channel of an EthercatCanGateway as a CanTransport. The gateway must outlive it.
class EthercatCanTransport final : public CanTransport {
 public:
  /// Throws std::out_of_range if `channel` is not in [0, gateway.channelCount()).
  EthercatCanTransport(EthercatCanGateway& gateway, int channel, const std::string& name);
  TxStatus send(const CanFrame& frame) noexcept override;
  RxStatus receive(CanFrame& out) noexcept override;
  bool restart() noexcept override;

 private:
  EthercatCanGateway& gw_;
  int channel_;
};

}  // namespace pmg::hal::bus
