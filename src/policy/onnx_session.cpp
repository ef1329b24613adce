#include "pmg/policy/onnx_session.hpp"

#include <cstring>
#include <stdexcept>

#include <onnxruntime_c_api.h>

namespace pmg::policy {
namespace {

const OrtApi& api() {
  static const OrtApi* a = OrtGetApiBase()->GetApi(ORT_API_VERSION);
  if (a == nullptr) {
    throw std::runtime_error(std::string("ONNX Runtime library does not provide C API version ") +
                             std::to_string(ORT_API_VERSION) + " (runtime " +
                             OrtGetApiBase()->GetVersionString() + ")");
  }
  return *a;
}

/// Throws on a non-null status (setup path only).
void check(OrtStatus* status, const std::string& context) {
  if (status == nullptr) return;
  std::string msg = context + ": " + api().GetErrorMessage(status);
  api().ReleaseStatus(status);
  throw std::runtime_error(msg);
}

template <typename T, void (*Release)(T*)>
struct Handle {
  T* p = nullptr;
  Handle() = default;
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (p != nullptr) Release(p);
  }
};

void releaseEnv(OrtEnv* p) { api().ReleaseEnv(p); }
void releaseSession(OrtSession* p) { api().ReleaseSession(p); }
void releaseOptions(OrtSessionOptions* p) { api().ReleaseSessionOptions(p); }
void releaseBinding(OrtIoBinding* p) { api().ReleaseIoBinding(p); }
void releaseValue(OrtValue* p) { api().ReleaseValue(p); }
void releaseMemInfo(OrtMemoryInfo* p) { api().ReleaseMemoryInfo(p); }
void releaseRunOptions(OrtRunOptions* p) { api().ReleaseRunOptions(p); }
void releaseMetadata(OrtModelMetadata* p) { api().ReleaseModelMetadata(p); }
void releaseTypeInfo(OrtTypeInfo* p) { api().ReleaseTypeInfo(p); }

/// One process-wide ORT environment (ORT allows only one), created on first use.
OrtEnv* sharedEnv() {
  static Handle<OrtEnv, releaseEnv> env;
  static bool created = [] {
    check(api().CreateEnv(ORT_LOGGING_LEVEL_WARNING, "pmg_policy", &env.p), "ONNX Runtime CreateEnv");
    return true;
  }();
  (void)created;
  return env.p;
}

}  // namespace

struct OnnxSession::Impl {
  std::string path;
  Handle<OrtSession, releaseSession> session;
  Handle<OrtIoBinding, releaseBinding> binding;
  Handle<OrtMemoryInfo, releaseMemInfo> mem_info;
  Handle<OrtRunOptions, releaseRunOptions> run_options;
  std::vector<std::unique_ptr<Handle<OrtValue, releaseValue>>> values;
  std::vector<TensorInfo> inputs, outputs;
  char error[256] = {0};

  TensorInfo info(bool input, std::size_t i) {
    OrtAllocator* alloc = nullptr;
    check(api().GetAllocatorWithDefaultOptions(&alloc), path);
    char* name = nullptr;
    check(input ? api().SessionGetInputName(session.p, i, alloc, &name)
                : api().SessionGetOutputName(session.p, i, alloc, &name),
          path + ": reading graph I/O name");
    TensorInfo t;
    t.name = name;
    check(api().AllocatorFree(alloc, name), path);
    Handle<OrtTypeInfo, releaseTypeInfo> type;
    check(input ? api().SessionGetInputTypeInfo(session.p, i, &type.p)
                : api().SessionGetOutputTypeInfo(session.p, i, &type.p),
          path + ": reading type of '" + t.name + "'");
    const OrtTensorTypeAndShapeInfo* tensor = nullptr;
    check(api().CastTypeInfoToTensorInfo(type.p, &tensor), path);
    if (tensor == nullptr) return t;  // not a tensor: is_float32 stays false, shape empty
    ONNXTensorElementDataType elem{};
    check(api().GetTensorElementType(tensor, &elem), path);
    t.is_float32 = elem == ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT;
    std::size_t dims = 0;
    check(api().GetDimensionsCount(tensor, &dims), path);
    t.shape.resize(dims);
    check(api().GetDimensions(tensor, t.shape.data(), dims), path);
    return t;
  }

  OrtValue* makeValue(const std::string& name, float* data, const std::vector<std::int64_t>& shape) {
    std::size_t n = 1;
    for (auto d : shape) {
      if (d <= 0) throw std::runtime_error(path + ": tensor '" + name + "': bound shape must be positive");
      n *= static_cast<std::size_t>(d);
    }
    auto v = std::make_unique<Handle<OrtValue, releaseValue>>();
    check(api().CreateTensorWithDataAsOrtValue(mem_info.p, data, n * sizeof(float), shape.data(), shape.size(),
                                               ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT, &v->p),
          path + ": creating tensor '" + name + "'");
    values.push_back(std::move(v));
    return values.back()->p;
  }
};

OnnxSession::OnnxSession(const std::string& model_path) : impl_(std::make_unique<Impl>()) {
  impl_->path = model_path;
  OrtEnv* env = sharedEnv();
  Handle<OrtSessionOptions, releaseOptions> opts;
  check(api().CreateSessionOptions(&opts.p), model_path);
  check(api().SetIntraOpNumThreads(opts.p, 1), model_path + ": SetIntraOpNumThreads");
  check(api().SetInterOpNumThreads(opts.p, 1), model_path + ": SetInterOpNumThreads");
  check(api().SetSessionExecutionMode(opts.p, ORT_SEQUENTIAL), model_path);
  check(api().SetSessionGraphOptimizationLevel(opts.p, ORT_ENABLE_ALL), model_path);
  // With one thread there is no pool to spin; keep it explicit so no core is ever busy-waited.
  check(api().AddSessionConfigEntry(opts.p, "session.intra_op.allow_spinning", "0"), model_path);
  check(api().AddSessionConfigEntry(opts.p, "session.inter_op.allow_spinning", "0"), model_path);
  check(api().CreateSession(env, model_path.c_str(), opts.p, &impl_->session.p), model_path + ": cannot load ONNX model");
  check(api().CreateCpuMemoryInfo(OrtDeviceAllocator, OrtMemTypeDefault, &impl_->mem_info.p), model_path);
  check(api().CreateIoBinding(impl_->session.p, &impl_->binding.p), model_path);
  check(api().CreateRunOptions(&impl_->run_options.p), model_path);

  std::size_t n_in = 0, n_out = 0;
  check(api().SessionGetInputCount(impl_->session.p, &n_in), model_path);
  check(api().SessionGetOutputCount(impl_->session.p, &n_out), model_path);
  for (std::size_t i = 0; i < n_in; ++i) impl_->inputs.push_back(impl_->info(true, i));
  for (std::size_t i = 0; i < n_out; ++i) impl_->outputs.push_back(impl_->info(false, i));
}

OnnxSession::~OnnxSession() = default;

const std::vector<TensorInfo>& OnnxSession::inputs() const noexcept { return impl_->inputs; }
const std::vector<TensorInfo>& OnnxSession::outputs() const noexcept { return impl_->outputs; }
const std::string& OnnxSession::path() const noexcept { return impl_->path; }

bool OnnxSession::metadata(const std::string& key, std::string* value) const {
  Handle<OrtModelMetadata, releaseMetadata> meta;
  check(api().SessionGetModelMetadata(impl_->session.p, &meta.p), impl_->path + ": reading metadata");
  OrtAllocator* alloc = nullptr;
  check(api().GetAllocatorWithDefaultOptions(&alloc), impl_->path);
  char* text = nullptr;
  check(api().ModelMetadataLookupCustomMetadataMap(meta.p, alloc, key.c_str(), &text), impl_->path);
  if (text == nullptr) return false;
  *value = text;
  check(api().AllocatorFree(alloc, text), impl_->path);
  return true;
}

void OnnxSession::bindInput(const std::string& name, float* data, const std::vector<std::int64_t>& shape) {
  OrtValue* v = impl_->makeValue(name, data, shape);
  check(api().BindInput(impl_->binding.p, name.c_str(), v), impl_->path + ": binding input '" + name + "'");
}

void OnnxSession::bindOutput(const std::string& name, float* data, const std::vector<std::int64_t>& shape) {
  OrtValue* v = impl_->makeValue(name, data, shape);
  check(api().BindOutput(impl_->binding.p, name.c_str(), v), impl_->path + ": binding output '" + name + "'");
}

bool OnnxSession::run() noexcept {
  OrtStatus* status = api().RunWithBinding(impl_->session.p, impl_->run_options.p, impl_->binding.p);
  if (status == nullptr) {
    impl_->error[0] = '\0';
    return true;
  }
  std::strncpy(impl_->error, api().GetErrorMessage(status), sizeof(impl_->error) - 1);
  impl_->error[sizeof(impl_->error) - 1] = '\0';
  api().ReleaseStatus(status);
  return false;
}

const char* OnnxSession::errorMessage() const noexcept { return impl_->error; }

}  // namespace pmg::policy
