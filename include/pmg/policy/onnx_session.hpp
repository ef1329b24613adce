#pragma once
/// @file onnx_session.hpp
/// RAII wrapper of one ONNX Runtime inference session (C API), built for a real-time loop.
///
/// Setup (constructor, bind) may allocate and throws std::runtime_error naming the model file.
/// The session uses 1 intra-op and 1 inter-op thread (the caller's thread does the work),
/// sequential execution and full graph optimisation. Inputs and outputs are float32 tensors
/// over caller-owned buffers, bound once through an IoBinding; run() then reads and writes those
/// buffers in place, is noexcept and reports failure through its return value.
/// ONNX Runtime headers stay private (src/policy), so users need only this header.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace pmg::policy {

/// Shape and name of one graph input or output.
struct TensorInfo {
  std::string name;
  std::vector<std::int64_t> shape;  ///< -1 for symbolic dimensions
  bool is_float32 = false;
};

class OnnxSession {
 public:
  /// Loads the model file. @throws std::runtime_error "<path>: ..." if ONNX Runtime refuses it.
  explicit OnnxSession(const std::string& model_path);
  ~OnnxSession();
  OnnxSession(const OnnxSession&) = delete;
  OnnxSession& operator=(const OnnxSession&) = delete;

  const std::vector<TensorInfo>& inputs() const noexcept;
  const std::vector<TensorInfo>& outputs() const noexcept;

  /// Looks up a custom metadata entry (ONNX metadata_props). @return false if absent.
  bool metadata(const std::string& key, std::string* value) const;

  /// Binds a float32 input tensor of `shape` over `data` (caller keeps it alive and sized
  /// product(shape)). @throws std::runtime_error on an unknown name or ORT failure.
  void bindInput(const std::string& name, float* data, const std::vector<std::int64_t>& shape);
  /// Binds a float32 output tensor over `data` (ORT writes the result there at each run()).
  void bindOutput(const std::string& name, float* data, const std::vector<std::int64_t>& shape);

  /// Runs the bound graph once. Real-time path: noexcept, no exceptions escape; ONNX Runtime
  /// allocates a few small bookkeeping objects per run (test_policy_alloc counts them).
  /// @return true on success; on failure errorMessage() holds ORT's message (truncated).
  bool run() noexcept;
  /// Last run() error text ("" after a success). Fixed buffer, no allocation.
  const char* errorMessage() const noexcept;

  /// Model file path (for messages).
  const std::string& path() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pmg::policy
