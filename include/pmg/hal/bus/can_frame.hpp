#pragma once
/// @file can_frame.hpp
/// @brief Transport-neutral CAN / CAN FD frame used by every pmg bus transport and motor protocol.
///
/// Plain value type (no heap), layout independent of Linux `struct can_frame` / `canfd_frame` so the
/// codecs compile and test on any platform. Transports convert at their boundary.

#include <array>
#include <cstdint>

namespace pmg::hal::bus {

/// Maximum payload of a CAN FD frame [bytes] (ISO 11898-1:2015).
inline constexpr std::size_t kCanFdMaxPayload = 64;
/// Maximum payload of a classic CAN frame [bytes].
inline constexpr std::size_t kCanMaxPayload = 8;

/// One CAN or CAN FD data frame, or an error indication reported by a transport.
struct CanFrame {
  /// Arbitration identifier: 11 bit (0..0x7FF) unless `extended` is set (29 bit, 0..0x1FFFFFFF).
  std::uint32_t id = 0;
  /// Payload length [bytes]: 0..8 for classic CAN; for CAN FD one of 0..8,12,16,20,24,32,48,64.
  std::uint8_t len = 0;
  bool extended = false;  ///< 29-bit identifier.
  bool fd = false;        ///< CAN FD frame (FDF bit).
  bool brs = false;       ///< CAN FD bit-rate switch in the data phase.
  /// Error indication (not a data frame): `id` carries an ErrorClass bit mask, payload unused.
  bool error = false;
  std::array<std::uint8_t, kCanFdMaxPayload> data{};  ///< Payload; bytes >= len are ignored.
};

/// Error classes a transport can report through an error CanFrame (`id` bit mask).
enum ErrorClass : std::uint32_t {
  kErrorBusOff = 1u << 0,      ///< Controller entered bus-off (TEC > 255); no traffic until restart.
  kErrorPassive = 1u << 1,     ///< Controller is error-passive (TEC or REC > 127).
  kErrorRestarted = 1u << 2,   ///< Controller left bus-off after a restart.
  kErrorTxTimeout = 1u << 3,   ///< A frame was not acknowledged in time.
  kErrorProtocol = 1u << 4,    ///< Bit/stuff/form/CRC error seen on the wire.
  kErrorRxOverflow = 1u << 5,  ///< Receive buffer overflow: frames were lost.
};

/// True when `len` is a legal CAN FD payload length (0..8,12,16,20,24,32,48,64 bytes).
constexpr bool isValidFdLength(std::size_t len) noexcept {
  return len <= 8 || len == 12 || len == 16 || len == 20 || len == 24 || len == 32 || len == 48 ||
         len == 64;
}

/// Smallest legal CAN FD payload length >= `len` (the driver pads with zeros); 64 if len > 64.
constexpr std::size_t fdPaddedLength(std::size_t len) noexcept {
  if (len <= 8) return len;
  constexpr std::size_t kSteps[] = {12, 16, 20, 24, 32, 48, 64};
  for (std::size_t s : kSteps) {
    if (len <= s) return s;
  }
  return 64;
}

}  // namespace pmg::hal::bus
