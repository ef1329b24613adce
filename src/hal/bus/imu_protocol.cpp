#include "pmg/hal/bus/imu_protocol.hpp"

#include <cmath>
#include <cstring>

namespace pmg::hal::bus {

namespace {
void putF(std::uint8_t* p, double v) noexcept {
  const float f = static_cast<float>(v);
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(u >> (8 * i));
}
double getF(const std::uint8_t* p) noexcept {
  std::uint32_t u = 0;
  for (int i = 0; i < 4; ++i) u |= static_cast<std::uint32_t>(p[i]) << (8 * i);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
}  // namespace

void encodeImu(const pmg::ImuState& imu, std::uint32_t seq, CanFrame& out) noexcept {
  out = CanFrame{};
  out.id = kImuCanId;
  out.fd = out.brs = true;
  out.len = 48;
  for (int i = 0; i < 4; ++i) out.data[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(seq >> (8 * i));
  for (int i = 0; i < 4; ++i) putF(&out.data[4 + 4 * i], imu.quat_wxyz[static_cast<std::size_t>(i)]);
  for (int i = 0; i < 3; ++i) putF(&out.data[20 + 4 * i], imu.gyro[static_cast<std::size_t>(i)]);
  for (int i = 0; i < 3; ++i) putF(&out.data[32 + 4 * i], imu.acc[static_cast<std::size_t>(i)]);
}

bool decodeImu(const CanFrame& f, pmg::ImuState& imu, std::uint32_t& seq) noexcept {
  if (f.error || !f.fd || f.extended || f.id != kImuCanId || f.len != 48) return false;
  pmg::ImuState s;
  for (int i = 0; i < 4; ++i) s.quat_wxyz[static_cast<std::size_t>(i)] = getF(&f.data[4 + 4 * i]);
  for (int i = 0; i < 3; ++i) s.gyro[static_cast<std::size_t>(i)] = getF(&f.data[20 + 4 * i]);
  for (int i = 0; i < 3; ++i) s.acc[static_cast<std::size_t>(i)] = getF(&f.data[32 + 4 * i]);
  for (double v : s.quat_wxyz) if (!std::isfinite(v)) return false;
  for (double v : s.gyro) if (!std::isfinite(v)) return false;
  for (double v : s.acc) if (!std::isfinite(v)) return false;
  s.valid = true;
  std::uint32_t q = 0;
  for (int i = 0; i < 4; ++i) q |= static_cast<std::uint32_t>(f.data[static_cast<std::size_t>(i)]) << (8 * i);
  imu = s;
  seq = q;
  return true;
}

}  // namespace pmg::hal::bus
