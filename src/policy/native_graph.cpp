#include "pmg/policy/native_graph.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace pmg::policy {
namespace {

/// Minimal protobuf wire-format reader (setup only).
class Wire {
 public:
  Wire(const char* p, std::size_t n, const std::string& where) : p_(p), end_(p + n), where_(where) {}
  bool done() const { return p_ >= end_; }
  std::uint64_t varint() {
    std::uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      need(1);
      const auto b = static_cast<std::uint8_t>(*p_++);
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if ((b & 0x80) == 0) return v;
    }
    fail("bad varint");
  }
  void field(int* number, int* type) {
    const std::uint64_t key = varint();
    *number = static_cast<int>(key >> 3);
    *type = static_cast<int>(key & 7);
  }
  Wire bytes() {
    const auto n = static_cast<std::size_t>(varint());
    need(n);
    Wire w(p_, n, where_);
    p_ += n;
    return w;
  }
  std::string str() {
    Wire w = bytes();
    return std::string(w.p_, w.end_);
  }
  std::uint32_t fixed32() {
    need(4);
    std::uint32_t v;
    std::memcpy(&v, p_, 4);
    p_ += 4;
    return v;
  }
  void skip(int type) {
    switch (type) {
      case 0: varint(); break;
      case 1: need(8); p_ += 8; break;
      case 2: bytes(); break;
      case 5: need(4); p_ += 4; break;
      default: fail("unsupported protobuf wire type " + std::to_string(type));
    }
  }
  const char* data() const { return p_; }
  std::size_t size() const { return static_cast<std::size_t>(end_ - p_); }
  [[noreturn]] void fail(const std::string& m) const { throw std::runtime_error(where_ + ": ONNX parse error: " + m); }

 private:
  void need(std::size_t n) const {
    if (static_cast<std::size_t>(end_ - p_) < n) fail("truncated message");
  }
  const char* p_;
  const char* end_;
  std::string where_;
};

struct Tensor {
  std::vector<std::int64_t> dims;
  int type = 0;  // 1 float, 7 int64
  std::vector<float> f;
  std::vector<std::int64_t> i;
};

Tensor readTensor(Wire w, std::string* name) {
  Tensor t;
  std::string raw;
  while (!w.done()) {
    int num, type;
    w.field(&num, &type);
    if (num == 1 && type == 0) {
      t.dims.push_back(static_cast<std::int64_t>(w.varint()));
    } else if (num == 1 && type == 2) {
      Wire p = w.bytes();
      while (!p.done()) t.dims.push_back(static_cast<std::int64_t>(p.varint()));
    } else if (num == 2 && type == 0) {
      t.type = static_cast<int>(w.varint());
    } else if (num == 4 && type == 2) {
      Wire p = w.bytes();
      while (!p.done()) {
        const std::uint32_t u = p.fixed32();
        float v;
        std::memcpy(&v, &u, 4);
        t.f.push_back(v);
      }
    } else if (num == 4 && type == 5) {
      const std::uint32_t u = w.fixed32();
      float v;
      std::memcpy(&v, &u, 4);
      t.f.push_back(v);
    } else if (num == 7 && type == 2) {
      Wire p = w.bytes();
      while (!p.done()) t.i.push_back(static_cast<std::int64_t>(p.varint()));
    } else if (num == 7 && type == 0) {
      t.i.push_back(static_cast<std::int64_t>(w.varint()));
    } else if (num == 8 && type == 2) {
      *name = w.str();
    } else if (num == 9 && type == 2) {
      raw = w.str();
    } else {
      w.skip(type);
    }
  }
  if (!raw.empty()) {
    if (t.type == 1) {
      t.f.resize(raw.size() / 4);
      std::memcpy(t.f.data(), raw.data(), t.f.size() * 4);
    } else if (t.type == 7) {
      t.i.resize(raw.size() / 8);
      std::memcpy(t.i.data(), raw.data(), t.i.size() * 8);
    }
  }
  return t;
}

struct RawNode {
  std::vector<std::string> in, out;
  std::string op;
  std::map<std::string, float> fattr;
  std::map<std::string, std::int64_t> iattr;
};

RawNode readNode(Wire w) {
  RawNode n;
  while (!w.done()) {
    int num, type;
    w.field(&num, &type);
    if (num == 1 && type == 2) {
      n.in.push_back(w.str());
    } else if (num == 2 && type == 2) {
      n.out.push_back(w.str());
    } else if (num == 4 && type == 2) {
      n.op = w.str();
    } else if (num == 5 && type == 2) {
      Wire a = w.bytes();
      std::string name;
      while (!a.done()) {
        int an, at;
        a.field(&an, &at);
        if (an == 1 && at == 2) {
          name = a.str();
        } else if (an == 2 && at == 5) {
          const std::uint32_t u = a.fixed32();
          float v;
          std::memcpy(&v, &u, 4);
          n.fattr[name] = v;
        } else if (an == 3 && at == 0) {
          n.iattr[name] = static_cast<std::int64_t>(a.varint());
        } else {
          a.skip(at);
        }
      }
    } else {
      w.skip(type);
    }
  }
  return n;
}

}  // namespace

NativeGraph::NativeGraph(const std::string& path, const std::string& input, const std::string& output, int input_size)
    : input_size_(input_size) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string bytes = ss.str();
  Wire model(bytes.data(), bytes.size(), path);
  std::string graph;
  while (!model.done()) {
    int num, type;
    model.field(&num, &type);
    if (num == 7 && type == 2) graph = model.str(); else model.skip(type);
  }
  if (graph.empty()) throw std::runtime_error(path + ": no graph in the ONNX model");
  std::vector<RawNode> raw_nodes;
  std::map<std::string, Tensor> inits;
  Wire g(graph.data(), graph.size(), path);
  while (!g.done()) {
    int num, type;
    g.field(&num, &type);
    if (num == 1 && type == 2) {
      raw_nodes.push_back(readNode(g.bytes()));
    } else if (num == 5 && type == 2) {
      std::string name;
      Tensor t = readTensor(g.bytes(), &name);
      inits[name] = std::move(t);
    } else {
      g.skip(type);
    }
  }

  std::map<std::string, int> index;
  auto addValue = [&](const std::string& name, int rows, int cols, const std::vector<float>* data) {
    index[name] = static_cast<int>(values_.size());
    values_.emplace_back(data != nullptr ? *data : std::vector<float>(static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols), 0.0f));
    rows_.push_back(rows);
    cols_.push_back(cols);
    return index[name];
  };
  input_ = addValue(input, 1, input_size, nullptr);
  auto fail = [&](const RawNode& n, const std::string& m) -> void {
    throw std::runtime_error(path + ": native backend: node " + n.op + " -> " + (n.out.empty() ? "?" : n.out[0]) + ": " + m);
  };
  auto operand = [&](const RawNode& n, std::size_t k) -> int {
    if (k >= n.in.size() || n.in[k].empty()) return -1;
    const auto it = index.find(n.in[k]);
    if (it != index.end()) return it->second;
    const auto t = inits.find(n.in[k]);
    if (t == inits.end() || t->second.type != 1) fail(n, "input '" + n.in[k] + "' is neither a computed value nor a float initializer");
    const auto& d = t->second.dims;
    const int rows = d.size() == 2 ? static_cast<int>(d[0]) : 1;
    const int cols = d.empty() ? 1 : static_cast<int>(d.back());
    if (d.size() > 2 || static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) != t->second.f.size()) fail(n, "initializer '" + n.in[k] + "' has an unsupported shape");
    return addValue(n.in[k], rows, cols, &t->second.f);
  };
  auto ints = [&](const RawNode& n, std::size_t k) -> std::vector<std::int64_t> {
    if (k >= n.in.size() || n.in[k].empty()) return {};
    const auto t = inits.find(n.in[k]);
    if (t == inits.end() || t->second.type != 7 || t->second.i.empty()) fail(n, "'" + n.in[k] + "' must be an int64 initializer");
    return t->second.i;
  };

  static const std::map<std::string, Op> kOps = {
      {"Sub", Op::kSub},   {"Div", Op::kDiv},         {"Add", Op::kAdd},   {"Mul", Op::kMul},
      {"Gemm", Op::kGemm}, {"Tanh", Op::kTanh},       {"Sigmoid", Op::kSigmoid}, {"Relu", Op::kRelu},
      {"Elu", Op::kElu},   {"Sqrt", Op::kSqrt},       {"Identity", Op::kIdentity}, {"Slice", Op::kSlice}};
  for (const RawNode& n : raw_nodes) {
    const auto op = kOps.find(n.op);
    if (op == kOps.end()) fail(n, "op not supported by the native backend");
    if (n.out.size() != 1) fail(n, "expected one output");
    Node node;
    node.op = op->second;
    int out_cols = 0;
    switch (node.op) {
      case Op::kSub: case Op::kDiv: case Op::kAdd: case Op::kMul: {
        node.a = operand(n, 0);
        node.b = operand(n, 1);
        const int ca = cols_[static_cast<std::size_t>(node.a)], cb = cols_[static_cast<std::size_t>(node.b)];
        if (rows_[static_cast<std::size_t>(node.a)] != 1 || rows_[static_cast<std::size_t>(node.b)] != 1 || (ca != cb && ca != 1 && cb != 1)) fail(n, "operands must be broadcastable batch-1 vectors");
        out_cols = std::max(ca, cb);
        break;
      }
      case Op::kGemm: {
        node.a = operand(n, 0);
        node.b = operand(n, 1);
        node.c = operand(n, 2);
        node.trans_b = n.iattr.count("transB") && n.iattr.at("transB") != 0;
        if ((n.iattr.count("transA") && n.iattr.at("transA") != 0) || (n.fattr.count("alpha") && n.fattr.at("alpha") != 1.0f) ||
            (n.fattr.count("beta") && n.fattr.at("beta") != 1.0f))
          fail(n, "only alpha = beta = 1, transA = 0 supported");
        const int k = cols_[static_cast<std::size_t>(node.a)];
        const int br = rows_[static_cast<std::size_t>(node.b)], bc = cols_[static_cast<std::size_t>(node.b)];
        if (rows_[static_cast<std::size_t>(node.a)] != 1 || (node.trans_b ? bc : br) != k) fail(n, "shape mismatch");
        out_cols = node.trans_b ? br : bc;
        if (node.c >= 0 && cols_[static_cast<std::size_t>(node.c)] != out_cols && cols_[static_cast<std::size_t>(node.c)] != 1) fail(n, "bias shape mismatch");
        break;
      }
      case Op::kSlice: {
        node.a = operand(n, 0);
        const int nc = cols_[static_cast<std::size_t>(node.a)];
        // Batch-1 vectors [1, n]: slice along the last axis; a slice over the batch axis must
        // keep the one row. starts/ends/axes/steps as ONNX Slice-13 (axes default 0..r-1).
        const auto starts = ints(n, 1), ends = ints(n, 2), steps = ints(n, 4);
        auto axes = ints(n, 3);
        if (axes.empty()) for (std::size_t i = 0; i < starts.size(); ++i) axes.push_back(static_cast<std::int64_t>(i));
        if (starts.size() != ends.size() || axes.size() != starts.size()) fail(n, "starts/ends/axes sizes differ");
        for (auto st : steps) if (st != 1) fail(n, "only step 1 supported");
        std::int64_t b = 0, e = nc;
        for (std::size_t i = 0; i < axes.size(); ++i) {
          if (axes[i] == 1 || axes[i] == -1) {
            b = starts[i];
            e = ends[i];
          } else if (axes[i] == 0 || axes[i] == -2) {
            if (starts[i] > 0 || ends[i] < 1) fail(n, "slicing away the batch row is not supported");
          } else {
            fail(n, "unsupported slice axis");
          }
        }
        if (b < 0) b += nc;
        if (e < 0) e += nc;
        b = std::clamp<std::int64_t>(b, 0, nc);
        e = std::clamp<std::int64_t>(e, b, nc);
        node.slice_begin = static_cast<int>(b);
        out_cols = static_cast<int>(e - b);
        break;
      }
      default:
        node.a = operand(n, 0);
        node.alpha = n.fattr.count("alpha") ? n.fattr.at("alpha") : 1.0f;
        out_cols = cols_[static_cast<std::size_t>(node.a)];
    }
    if (out_cols <= 0) fail(n, "empty output");
    node.out = addValue(n.out[0], 1, out_cols, nullptr);
    nodes_.push_back(node);
  }
  const auto it = index.find(output);
  if (it == index.end()) throw std::runtime_error(path + ": native backend: graph output '" + output + "' is not computed");
  output_ = it->second;
}

int NativeGraph::outputSize() const noexcept { return cols_[static_cast<std::size_t>(output_)]; }

void NativeGraph::run(const float* in, float* out) noexcept {
  std::copy(in, in + input_size_, values_[static_cast<std::size_t>(input_)].begin());
  for (const Node& n : nodes_) {
    float* y = values_[static_cast<std::size_t>(n.out)].data();
    const int ny = cols_[static_cast<std::size_t>(n.out)];
    const float* a = values_[static_cast<std::size_t>(n.a)].data();
    const int na = cols_[static_cast<std::size_t>(n.a)];
    switch (n.op) {
      case Op::kSub: case Op::kDiv: case Op::kAdd: case Op::kMul: {
        const float* b = values_[static_cast<std::size_t>(n.b)].data();
        const int nb = cols_[static_cast<std::size_t>(n.b)];
        for (int i = 0; i < ny; ++i) {
          const float x = a[na == 1 ? 0 : i], z = b[nb == 1 ? 0 : i];
          y[i] = n.op == Op::kSub ? x - z : n.op == Op::kDiv ? x / z : n.op == Op::kAdd ? x + z : x * z;
        }
        break;
      }
      case Op::kGemm: {
        const float* w = values_[static_cast<std::size_t>(n.b)].data();
        const int wc = cols_[static_cast<std::size_t>(n.b)];
        const float* c = n.c >= 0 ? values_[static_cast<std::size_t>(n.c)].data() : nullptr;
        const int ncb = n.c >= 0 ? cols_[static_cast<std::size_t>(n.c)] : 0;
        for (int j = 0; j < ny; ++j) y[j] = c != nullptr ? c[ncb == 1 ? 0 : j] : 0.0f;
        if (n.trans_b) {
          for (int j = 0; j < ny; ++j) {
            float s = 0.0f;
            for (int k = 0; k < na; ++k) s += a[k] * w[j * wc + k];
            y[j] += s;
          }
        } else {
          for (int k = 0; k < na; ++k) {
            const float ak = a[k];
            const float* row = w + static_cast<std::ptrdiff_t>(k) * wc;
            for (int j = 0; j < ny; ++j) y[j] += ak * row[j];
          }
        }
        break;
      }
      case Op::kTanh: for (int i = 0; i < ny; ++i) y[i] = std::tanh(a[i]); break;
      case Op::kSigmoid: for (int i = 0; i < ny; ++i) y[i] = 1.0f / (1.0f + std::exp(-a[i])); break;
      case Op::kRelu: for (int i = 0; i < ny; ++i) y[i] = std::max(a[i], 0.0f); break;
      case Op::kElu: for (int i = 0; i < ny; ++i) y[i] = a[i] >= 0.0f ? a[i] : n.alpha * (std::exp(a[i]) - 1.0f); break;
      case Op::kSqrt: for (int i = 0; i < ny; ++i) y[i] = std::sqrt(a[i]); break;
      case Op::kIdentity: std::copy(a, a + ny, y); break;
      case Op::kSlice: std::copy(a + n.slice_begin, a + n.slice_begin + ny, y); break;
    }
  }
  const auto& o = values_[static_cast<std::size_t>(output_)];
  std::copy(o.begin(), o.end(), out);
}

}  // namespace pmg::policy
