#pragma once
/// @file imu_protocol.hpp
/// @brief IMU sample in one CAN FD frame (used between pmg_sil and the CAN backend; a real IMU on
/// CAN FD can be bridged to it, or another IMU reader fills pmg::ImuState directly).
///
/// Frame: 11-bit id kImuCanId, FD with BRS, 48 bytes, little-endian:
///   0..3 sequence (uint32) | 4..19 quat_wxyz (4 x float32, world <- IMU) |
///   20..31 gyro [rad/s] (3 x float32, IMU frame) | 32..43 acc [m/s^2] (3 x float32, IMU frame) |
///   44..47 zero.
/// decodeImu() rejects frames with another id, length or kind, and non-finite values.

#include <cstdint>

#include "pmg/hal/bus/can_frame.hpp"
#include "pmg/hal/types.hpp"

namespace pmg::hal::bus {

inline constexpr std::uint32_t kImuCanId = 0x0F0;

/// Encode `imu` with sequence number `seq`.
void encodeImu(const pmg::ImuState& imu, std::uint32_t seq, CanFrame& out) noexcept;
/// Decode; on success writes `imu` (valid = true) and `seq`. False for a malformed frame.
bool decodeImu(const CanFrame& frame, pmg::ImuState& imu, std::uint32_t& seq) noexcept;

}  // namespace pmg::hal::bus
