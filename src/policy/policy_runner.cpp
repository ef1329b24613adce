#include "pmg/policy/policy_runner.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pmg::policy {
namespace {

bool allFinite(const std::vector<float>& v) noexcept {
  for (const float x : v) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

std::string shapeText(const std::vector<std::int64_t>& s) {
  std::ostringstream o;
  o << "[";
  for (std::size_t i = 0; i < s.size(); ++i) o << (i ? ", " : "") << s[i];
  o << "]";
  return o.str();
}

/// Accepts [n], [1, n], [-1, n] (symbolic batch) for a vector of n floats.
bool shapeFits(const std::vector<std::int64_t>& s, std::int64_t n) {
  if (s.size() == 1) return s[0] == n || s[0] < 0;
  if (s.size() == 2) return (s[0] == 1 || s[0] < 0) && (s[1] == n || s[1] < 0);
  return false;
}

}  // namespace

bool PolicyRunnerOptions::validate(std::string* message) const {
  auto fail = [&](const std::string& m) {
    if (message != nullptr) *message = m;
    return false;
  };
  if (warmup_runs < 0 || warmup_runs > 100000) return fail("PolicyRunnerOptions.warmup_runs must be in [0, 100000]");
  if (!(reference_atol > 0.0f) || !std::isfinite(reference_atol)) return fail("PolicyRunnerOptions.reference_atol must be > 0");
  if (!(reference_rtol >= 0.0f) || !std::isfinite(reference_rtol)) return fail("PolicyRunnerOptions.reference_rtol must be >= 0");
  return true;
}

PolicyRunner::PolicyRunner(const std::string& onnx_path, const PolicyRobotSpec& robot, const PolicyRunnerOptions& options) {
  std::string msg;
  if (!options.validate(&msg)) throw std::invalid_argument(msg);

  session_ = std::make_unique<OnnxSession>(onnx_path);
  std::string text;
  if (!session_->metadata(kContractMetadataKey, &text)) {
    throw ContractError(onnx_path, kContractMetadataKey, "missing from the ONNX metadata (export the actor with training/export_onnx.py)");
  }
  contract_ = parseContract(text, onnx_path);
  checkContract(contract_, robot, onnx_path);

  const auto n_obs = static_cast<std::int64_t>(contract_.observation.size());
  const auto n_act = static_cast<std::int64_t>(contract_.actuated_joints.size());
  if (session_->inputs().size() != 1 || session_->outputs().size() != 1) {
    throw std::runtime_error(onnx_path + ": graph must have exactly 1 input and 1 output, has " +
                             std::to_string(session_->inputs().size()) + " and " + std::to_string(session_->outputs().size()));
  }
  const TensorInfo& in = session_->inputs()[0];
  const TensorInfo& out = session_->outputs()[0];
  if (!in.is_float32 || !shapeFits(in.shape, n_obs)) {
    throw ContractError(onnx_path, "observation",
                        "contract describes " + std::to_string(n_obs) + " float32 inputs, graph input '" + in.name +
                            "' has shape " + shapeText(in.shape) + (in.is_float32 ? "" : " and is not float32"));
  }
  if (!out.is_float32 || !shapeFits(out.shape, n_act)) {
    throw ContractError(onnx_path, "actuated_joints",
                        "contract describes " + std::to_string(n_act) + " float32 actions, graph output '" + out.name +
                            "' has shape " + shapeText(out.shape) + (out.is_float32 ? "" : " and is not float32"));
  }
  input_.assign(static_cast<std::size_t>(n_obs), 0.0f);
  output_.assign(static_cast<std::size_t>(n_act), 0.0f);
  action_.assign(static_cast<std::size_t>(n_act), 0.0f);
  q_des_.assign(static_cast<std::size_t>(n_act), 0.0);
  const std::vector<std::int64_t> in_shape = in.shape.size() == 1 ? std::vector<std::int64_t>{n_obs} : std::vector<std::int64_t>{1, n_obs};
  const std::vector<std::int64_t> out_shape = out.shape.size() == 1 ? std::vector<std::int64_t>{n_act} : std::vector<std::int64_t>{1, n_act};
  session_->bindInput(in.name, input_.data(), in_shape);
  session_->bindOutput(out.name, output_.data(), out_shape);

  for (std::size_t p = 0; p < contract_.reference_pairs.size(); ++p) {
    const ReferencePair& ref = contract_.reference_pairs[p];
    std::copy(ref.obs.begin(), ref.obs.end(), input_.begin());
    if (!session_->run()) throw std::runtime_error(onnx_path + ": inference failed on reference pair " + std::to_string(p) + ": " + session_->errorMessage());
    for (std::size_t i = 0; i < output_.size(); ++i) {
      const float err = std::abs(output_[i] - ref.action[i]);
      if (!(err <= options.reference_atol + options.reference_rtol * std::abs(ref.action[i]))) {
        std::ostringstream o;
        o.precision(9);
        o << "model gives " << output_[i] << ", stored action is " << ref.action[i] << " (|diff| " << err << " > "
          << options.reference_atol << " + " << options.reference_rtol << " * |ref|; the model is not the one the contract was written for)";
        throw ContractError(onnx_path, "reference_pairs[" + std::to_string(p) + "].action[" + std::to_string(i) + "] (" + contract_.actuated_joints[i] + ")", o.str());
      }
      reference_max_abs_error_ = std::max(reference_max_abs_error_, err);
    }
  }
  if (options.backend == PolicyBackend::kNative) {
    native_ = std::make_unique<NativeGraph>(onnx_path, in.name, out.name, static_cast<int>(n_obs));
    if (native_->outputSize() != n_act) {
      throw std::runtime_error(onnx_path + ": native backend computes " + std::to_string(native_->outputSize()) +
                               " outputs, contract has " + std::to_string(n_act));
    }
    std::vector<float> ours(output_.size());
    for (std::size_t p = 0; p < contract_.reference_pairs.size(); ++p) {
      const ReferencePair& ref = contract_.reference_pairs[p];
      std::copy(ref.obs.begin(), ref.obs.end(), input_.begin());
      if (!session_->run()) throw std::runtime_error(onnx_path + ": inference failed: " + session_->errorMessage());
      native_->run(input_.data(), ours.data());
      for (std::size_t i = 0; i < ours.size(); ++i) {
        const float tol_ref = options.reference_atol + options.reference_rtol * std::abs(ref.action[i]);
        const float tol_ort = options.reference_atol + options.reference_rtol * std::abs(output_[i]);
        if (!(std::abs(ours[i] - ref.action[i]) <= tol_ref) || !(std::abs(ours[i] - output_[i]) <= tol_ort)) {
          std::ostringstream o;
          o.precision(9);
          o << "native backend gives " << ours[i] << ", ONNX Runtime " << output_[i] << ", stored action " << ref.action[i];
          throw ContractError(onnx_path, "reference_pairs[" + std::to_string(p) + "].action[" + std::to_string(i) + "] (native backend)", o.str());
        }
      }
    }
  }
  for (int w = 0; w < options.warmup_runs; ++w) {
    const ReferencePair& ref = contract_.reference_pairs[static_cast<std::size_t>(w) % contract_.reference_pairs.size()];
    std::copy(ref.obs.begin(), ref.obs.end(), input_.begin());
    if (!session_->run()) throw std::runtime_error(onnx_path + ": warm-up inference failed: " + session_->errorMessage());
    if (native_) native_->run(input_.data(), output_.data());
  }
  resetAction();
}

void PolicyRunner::resetAction() noexcept {
  std::fill(action_.begin(), action_.end(), 0.0f);
  updateTargets();
}

void PolicyRunner::updateTargets() noexcept {
  const ActionSpec& a = contract_.action;
  for (std::size_t i = 0; i < action_.size(); ++i) {
    q_des_[i] = a.offset[i] + a.scale[i] * static_cast<double>(std::clamp(action_[i], -a.clip, a.clip));
  }
}

PolicyStepStatus PolicyRunner::step(const float* obs) noexcept {
  ++counters_.steps;
  PolicyStepStatus status;
  std::copy(obs, obs + input_.size(), input_.begin());
  if (!allFinite(input_)) {
    ++counters_.nonfinite_observation;
    status.code = PolicyStepCode::kNonFiniteObservation;
  } else if (native_) {
    native_->run(input_.data(), output_.data());
  } else if (!session_->run()) {
    ++counters_.inference_errors;
    status.code = PolicyStepCode::kInferenceError;
  }
  if (status.ok() && !allFinite(output_)) {
    ++counters_.nonfinite_action;
    status.code = PolicyStepCode::kNonFiniteAction;
  }
  if (!status.ok()) {
    ++counters_.held;
    return status;
  }
  std::copy(output_.begin(), output_.end(), action_.begin());
  updateTargets();
  return status;
}

}  // namespace pmg::policy
