#pragma once
/// @file transport.hpp
/// @brief One interface for every way a CAN frame reaches a motor: Linux SocketCAN, CAN over UDP on
/// loopback (tests, SIL), and an EtherCAT-CAN bridge supplied by the user.
///
/// Construction (setup) may allocate and throws std::system_error / std::invalid_argument naming the
/// interface. send(), receive(), state() and restart() are cyclic: noexcept, non-blocking, no heap,
/// and report through status values and counters.

#include <cstdint>
#include <string>

#include "pmg/hal/bus/can_frame.hpp"

namespace pmg::hal::bus {

/// Outcome of CanTransport::send().
enum class TxStatus : std::uint8_t {
  kOk = 0,     ///< Frame handed to the driver / socket.
  kQueueFull,  ///< Transmit queue full (ENOBUFS/EAGAIN): frame dropped, try next cycle.
  kBusOff,     ///< Controller is bus-off: frame dropped until restart().
  kError,      ///< Any other failure (bad frame, interface down).
};

/// Outcome of CanTransport::receive().
enum class RxStatus : std::uint8_t {
  kFrame = 0,  ///< `out` holds a data frame or an error indication (CanFrame::error).
  kEmpty,      ///< Nothing pending.
  kError,      ///< Read failed or a malformed datagram was dropped (counted).
};

/// Controller fault confinement state (ISO 11898-1 section 12).
enum class BusState : std::uint8_t { kErrorActive = 0, kErrorPassive, kBusOff };

/// Monotonic counters, for telemetry.
struct TransportCounters {
  std::uint64_t tx_frames = 0;        ///< Frames accepted by send().
  std::uint64_t tx_queue_full = 0;    ///< send() answered kQueueFull.
  std::uint64_t tx_bus_off = 0;       ///< send() answered kBusOff.
  std::uint64_t tx_errors = 0;        ///< send() answered kError.
  std::uint64_t rx_frames = 0;        ///< Data frames received.
  std::uint64_t rx_error_frames = 0;  ///< Error indications received.
  std::uint64_t rx_errors = 0;        ///< Failed reads / malformed datagrams.
  std::uint64_t bus_off_events = 0;   ///< Transitions into bus-off.
  std::uint64_t restarts = 0;         ///< restart() requests issued.
};

/// Name of a state / status (static strings).
const char* toString(BusState s) noexcept;
const char* toString(TxStatus s) noexcept;

/// One CAN channel.
class CanTransport {
 public:
  virtual ~CanTransport() = default;
  CanTransport() = default;
  CanTransport(const CanTransport&) = delete;
  CanTransport& operator=(const CanTransport&) = delete;

  /// Channel name (interface name, or "udp:<port>").
  const std::string& name() const noexcept { return name_; }
  /// Queue one frame for transmission. Never blocks.
  virtual TxStatus send(const CanFrame& frame) noexcept = 0;
  /// Take the next received frame, if any. Never blocks. Error indications update state() and are
  /// returned as frames with `error` set and `id` = ErrorClass mask.
  virtual RxStatus receive(CanFrame& out) noexcept = 0;
  /// Current fault confinement state as last reported by the controller.
  BusState state() const noexcept { return state_; }
  /// Ask the controller to leave bus-off. Returns false if the request could not be issued.
  virtual bool restart() noexcept = 0;
  /// File descriptor to poll() for readability, or -1.
  virtual int pollFd() const noexcept { return -1; }
  const TransportCounters& counters() const noexcept { return counters_; }

 protected:
  /// Update state and counters from an error indication (ErrorClass mask). Shared by all transports.
  void applyErrorClass(std::uint32_t mask) noexcept;
  /// Counts a decoded frame: an error indication updates the state, a data frame the rx counter.
  /// Returns RxStatus::kFrame (the common end of every receive()).
  RxStatus acceptFrame(const CanFrame& frame) noexcept;
  std::string name_;
  BusState state_ = BusState::kErrorActive;
  TransportCounters counters_;
};

}  // namespace pmg::hal::bus
