#pragma once
/// @file backend.hpp
/// The seam between the HAL and what actually moves the joints: the MuJoCo SIL (in-process),
/// motor buses (CAN, see include/pmg/hal/bus/), or a test mock. One controller binary, one HAL;
/// only the backend changes (chosen in the controller config).

#include <string>

#include "pmg/hal/types.hpp"

namespace pmg {

/// Result of one backend exchange.
enum class BackendStatus : int {
  kOk = 0,
  kPartial = 1,   ///< some motors did not reply this cycle (their MotorState.valid is false)
  kFault = 2,     ///< the backend cannot deliver a state (bus down, simulation diverged)
};

/// A HAL backend. Setup (constructor/start) may allocate and throw; exchange() is called once per
/// HAL cycle (500 Hz) from the HAL thread and must be noexcept, allocation-free, non-blocking
/// beyond its own cycle budget.
class HalBackend {
 public:
  virtual ~HalBackend() = default;
  /// Backend name for logs, e.g. "mujoco", "can".
  virtual const char* name() const noexcept = 0;
  /// Cycle period the backend expects [s] (500 Hz: 0.002).
  virtual double cyclePeriod() const noexcept = 0;
  /// Sends @p command to the motors, advances one cycle (the SIL steps its physics by one
  /// cycle), and fills @p state with the replies and the IMU.
  virtual BackendStatus exchange(const LowCommand& command, LowState& state) noexcept = 0;
  /// Health report for the end-of-run summary, naming what went wrong in words (motors that never
  /// replied, rejected frames, ...); "" when there is nothing to report. Reporting side only (after
  /// a run): may allocate.
  virtual std::string report() const { return {}; }
};

}  // namespace pmg
