#pragma once
/// @file zero_offset_backend.hpp
/// Applies calibrated encoder zero offsets (RobotConfig joints' `zero_offset`, from pmg_calib_zero,
/// docs/calibration.md) around any HAL backend (MuJoCo SIL, CAN buses), so that everything above the
/// HAL sees true joint angles:
///   reported q = reading − offset,   commanded q = target + offset   [rad]
/// (offset = encoder reading − true angle). Velocities and torques are unchanged. exchange() is
/// noexcept and allocation-free (one LowCommand copy per cycle).

#include <array>
#include <memory>
#include <stdexcept>
#include <utility>

#include <Eigen/Core>

#include "pmg/hal/backend.hpp"

namespace pmg {

class ZeroOffsetBackend final : public HalBackend {
 public:
  /// @p offsets (n ≤ kMaxMotors) in joint order [rad]. Throws std::invalid_argument if @p inner is null,
  /// n > kMaxMotors or an offset is non-finite.
  ZeroOffsetBackend(std::unique_ptr<HalBackend> inner, const Eigen::VectorXd& offsets) : inner_(std::move(inner)) {
    if (!inner_) throw std::invalid_argument("ZeroOffsetBackend: inner backend must not be null");
    if (offsets.size() > kMaxMotors) throw std::invalid_argument("ZeroOffsetBackend: more offsets than kMaxMotors");
    if (!offsets.allFinite()) throw std::invalid_argument("ZeroOffsetBackend: offsets must be finite");
    n_ = static_cast<int>(offsets.size());
    for (int i = 0; i < n_; ++i) offsets_[static_cast<std::size_t>(i)] = offsets(i);
  }
  const char* name() const noexcept override { return inner_->name(); }
  double cyclePeriod() const noexcept override { return inner_->cyclePeriod(); }
  BackendStatus exchange(const LowCommand& command, LowState& state) noexcept override {
    cmd_ = command;
    for (int i = 0; i < n_ && i < cmd_.num_motors; ++i) cmd_.motors[static_cast<std::size_t>(i)].q += offsets_[static_cast<std::size_t>(i)];
    const BackendStatus s = inner_->exchange(cmd_, state);
    for (int i = 0; i < n_ && i < state.num_motors; ++i) state.motors[static_cast<std::size_t>(i)].q -= offsets_[static_cast<std::size_t>(i)];
    return s;
  }
  HalBackend& inner() noexcept { return *inner_; }

 private:
  std::unique_ptr<HalBackend> inner_;
  std::array<double, kMaxMotors> offsets_{};
  int n_ = 0;
  LowCommand cmd_{};
};

}  // namespace pmg
