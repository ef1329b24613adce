#pragma once
/// @file policy_runner.hpp
/// Runs an exported actor (ONNX, with its pmg.contract) in the controller's 100 Hz loop.
///
/// Setup (constructor; may allocate and throw):
///   1. loads the model with 1 intra-op / 1 inter-op thread (OnnxSession);
///   2. parses the contract from metadata and checks it against the robot (checkContract);
///   3. checks the graph has one float32 input (1 x obs) and one float32 output (1 x n_act);
///   4. preallocates input/output buffers and binds them once;
///   5. re-runs every stored reference pair and refuses to start if any action element differs
///      beyond |a - a_ref| <= atol + rtol * |a_ref|;
///   6. runs `warmup_runs` inferences so the first real tick pays no lazy initialisation;
///   7. with PolicyBackend::kNative: builds the allocation-free NativeGraph and requires it to
///      reproduce both ONNX Runtime and the reference actions to the same tolerance.
/// Loop: step() is noexcept, takes no locks, does no I/O and returns a status; on any failure it
/// keeps the last good action and counts it. pmg's code in step() allocates nothing; ONNX
/// Runtime 1.24's Run itself performs a constant 16 small operator-new calls per inference
/// (execution-frame bookkeeping; tensors are the bound buffers); with PolicyBackend::kNative the
/// whole tick allocates nothing. test_policy_alloc pins these facts (docs/policy.md).
///
/// Action -> targets (actuated order): q_des[i] = offset[i] + scale[i] * clamp(a[i], ±clip) [rad].

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pmg/policy/contract.hpp"
#include "pmg/policy/native_graph.hpp"
#include "pmg/policy/onnx_session.hpp"

namespace pmg::policy {

/// Which engine evaluates the actor in step(). Both are set up and cross-checked at load.
enum class PolicyBackend : std::uint8_t {
  kOnnxRuntime = 0,  ///< ONNX Runtime C API (IoBinding); allocates a little inside Run
  kNative,           ///< NativeGraph: allocation-free, supports the exporter's op set only
};

struct PolicyRunnerOptions {
  PolicyBackend backend = PolicyBackend::kOnnxRuntime;
  int warmup_runs = 20;          ///< inferences run at setup, >= 0
  float reference_atol = 1e-5f;  ///< absolute tolerance on reference actions, > 0
  float reference_rtol = 1e-4f;  ///< relative tolerance on reference actions, >= 0
  /// @return true if valid; otherwise false and *message names the bad field and range.
  bool validate(std::string* message) const;
};

enum class PolicyStepCode : std::uint8_t {
  kOk = 0,
  kNonFiniteObservation,  ///< an input value was NaN/Inf: actor not run, last action held
  kInferenceError,        ///< ONNX Runtime returned an error: last action held
  kNonFiniteAction,       ///< the actor produced NaN/Inf: last action held
};

/// Result of one step(). ok() == (code == kOk).
struct PolicyStepStatus {
  PolicyStepCode code = PolicyStepCode::kOk;
  bool ok() const noexcept { return code == PolicyStepCode::kOk; }
};

/// Counters for telemetry (monotonic since construction).
struct PolicyCounters {
  std::uint64_t steps = 0;               ///< step() calls
  std::uint64_t nonfinite_observation = 0;
  std::uint64_t inference_errors = 0;
  std::uint64_t nonfinite_action = 0;
  std::uint64_t held = 0;                ///< steps that kept the previous action (sum of the three above)
};

class PolicyRunner {
 public:
  /// @param onnx_path exported actor with `pmg.contract` metadata
  /// @param robot     robot/controller description the contract must match
  /// @throws ContractError (contract malformed or mismatching, reference pairs off) naming the
  ///         field; std::runtime_error (file/ORT problems, wrong graph I/O); std::invalid_argument
  ///         (options invalid).
  PolicyRunner(const std::string& onnx_path, const PolicyRobotSpec& robot, const PolicyRunnerOptions& options = {});

  const PolicyContract& contract() const noexcept { return contract_; }
  int observationSize() const noexcept { return static_cast<int>(input_.size()); }
  int actionSize() const noexcept { return static_cast<int>(output_.size()); }

  /// One actor inference. Real-time path: noexcept; allocations only inside ONNX Runtime's Run
  /// (see the file comment), none at all with PolicyBackend::kNative.
  /// @param obs (observationSize() x 1) actor input, already scaled (ObservationAssembler::data()).
  PolicyStepStatus step(const float* obs) noexcept;

  /// Raw actor output of the last good step, (actionSize() x 1); zeros before the first.
  const float* action() const noexcept { return action_.data(); }
  /// Joint position targets of the last good step [rad], (actionSize() x 1), actuated order;
  /// the action offset (default pose) before the first.
  const double* jointTargets() const noexcept { return q_des_.data(); }
  /// Resets the held action to zero (targets = offset), e.g. when the actor is re-engaged.
  void resetAction() noexcept;

  const PolicyCounters& counters() const noexcept { return counters_; }
  /// ONNX Runtime's message of the last inference error ("" if none).
  const char* lastError() const noexcept { return session_->errorMessage(); }

  /// Largest |a - a_ref| over the reference pairs, measured at load.
  float referenceMaxAbsError() const noexcept { return reference_max_abs_error_; }

 private:
  void updateTargets() noexcept;

  std::unique_ptr<OnnxSession> session_;
  std::unique_ptr<NativeGraph> native_;  // set iff options.backend == kNative
  PolicyContract contract_;
  std::vector<float> input_;   // bound to the graph input
  std::vector<float> output_;  // bound to the graph output
  std::vector<float> action_;  // last good action
  std::vector<double> q_des_;  // targets from action_
  PolicyCounters counters_;
  float reference_max_abs_error_ = 0.0f;
};

}  // namespace pmg::policy
