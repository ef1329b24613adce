#include "pmg/hal/hal_runner.hpp"

#include "pmg/hal/realtime.hpp"

namespace pmg {

HalRunner::HalRunner(std::unique_ptr<HalBackend> backend, int num_motors) : backend_(std::move(backend)) {
  command_.num_motors = num_motors;
  commands_.write(command_);  // zero gains: passive until the loop writes
}

BackendStatus HalRunner::cycle() noexcept {
  const double start = hal::rt::now();
  commands_.read(command_);
  const BackendStatus status = backend_->exchange(command_, state_);
  if (status == BackendStatus::kFault) fault_cycles_.fetch_add(1);
  state_.hal_runtime = last_runtime_;
  state_.hal_period = last_period_;
  state_.hal_overruns = overruns_;
  states_.write(state_);
  const double end = hal::rt::now();
  last_runtime_ = end - start;
  last_period_ = last_start_ > 0 ? start - last_start_ : 0.0;
  last_start_ = start;
  const bool overrun = last_runtime_ > backend_->cyclePeriod();
  if (overrun) ++overruns_;
  timing_.record(last_runtime_, last_period_, overrun);
  return status;
}

}  // namespace pmg
