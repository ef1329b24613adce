#pragma once
/// @file native_graph.hpp
/// Allocation-free evaluator of the small feed-forward actor graphs pmg exports, as an
/// alternative to ONNX Runtime inside the real-time loop (ORT's Run allocates; see docs/policy.md).
///
/// Setup reads the ONNX file itself (protobuf wire format: graph nodes and float/int64
/// initializers), accepts only a single-input, single-output graph of batch-1 vectors built from
/// Sub, Div, Add, Mul, Gemm (alpha = beta = 1, transA = 0, transB 0/1), Tanh, Sigmoid, Relu, Elu,
/// Sqrt, Identity and Slice (last axis, step 1), and preallocates one buffer per value.
/// run() is noexcept and allocation-free. PolicyRunner uses it only after checking it against
/// ONNX Runtime and the contract's reference pairs at load.

#include <cstdint>
#include <string>
#include <vector>

namespace pmg::policy {

class NativeGraph {
 public:
  /// @param model_path ONNX file; @param input, output graph input/output names;
  /// @param input_size number of floats of the input (batch 1).
  /// @throws std::runtime_error "<path>: ..." naming an unsupported op, attribute or shape.
  NativeGraph(const std::string& model_path, const std::string& input, const std::string& output, int input_size);

  int inputSize() const noexcept { return input_size_; }
  int outputSize() const noexcept;

  /// Evaluates the graph. @param in (inputSize()), @param out (outputSize()). noexcept, no allocation.
  void run(const float* in, float* out) noexcept;

 private:
  enum class Op : std::uint8_t { kSub, kDiv, kAdd, kMul, kGemm, kTanh, kSigmoid, kRelu, kElu, kSqrt, kIdentity, kSlice };
  struct Node {
    Op op;
    int a = -1, b = -1, c = -1;  // value indices (b, c: second/third operand or -1)
    int out = -1;
    bool trans_b = false;
    float alpha = 1.0f;
    int slice_begin = 0;
  };
  std::vector<Node> nodes_;
  std::vector<std::vector<float>> values_;  // one buffer per value (batch-1 vectors, matrices)
  std::vector<int> rows_, cols_;            // matrix shape of each value (vectors: rows = 1)
  int input_ = -1, output_ = -1, input_size_ = 0;
};

}  // namespace pmg::policy
