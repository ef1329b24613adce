#include "pmg/policy/observation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pmg::policy {

ObservationAssembler::ObservationAssembler(ObservationLayout layout) : layout_(std::move(layout)) {
  int off = 0;
  for (const auto& t : layout_.terms) {
    if (t.size <= 0 || t.scale.size() != static_cast<std::size_t>(t.size)) {
      throw std::invalid_argument("observation term '" + t.name + "': size must be > 0 with one scale per value");
    }
    offset_.push_back(off);
    off += t.size;
  }
  if (layout_.history_length < 1) throw std::invalid_argument("observation.history_length must be >= 1");
  frame_.assign(static_cast<std::size_t>(off), 0.0f);
  stacked_.assign(static_cast<std::size_t>(off) * static_cast<std::size_t>(layout_.history_length), 0.0f);
}

int ObservationAssembler::termIndex(const std::string& name) const {
  for (std::size_t i = 0; i < layout_.terms.size(); ++i) {
    if (layout_.terms[i].name == name) return static_cast<int>(i);
  }
  std::string known;
  for (const auto& t : layout_.terms) known += (known.empty() ? "" : ", ") + t.name;
  throw std::invalid_argument("observation term '" + name + "' is not in the policy contract (terms: " + known + ")");
}

int ObservationAssembler::termSize(int index) const noexcept { return layout_.terms[static_cast<std::size_t>(index)].size; }

template <typename T>
static void writeTerm(const ObservationTerm& t, float clip, const T* raw, float* out) noexcept {
  for (int k = 0; k < t.size; ++k) {
    const float v = static_cast<float>(raw[k]) * t.scale[static_cast<std::size_t>(k)];
    out[k] = std::isnan(v) ? v : std::clamp(v, -clip, clip);
  }
}

void ObservationAssembler::setTerm(int index, const double* raw) noexcept {
  const auto i = static_cast<std::size_t>(index);
  writeTerm(layout_.terms[i], layout_.clip, raw, frame_.data() + offset_[i]);
}

void ObservationAssembler::setTerm(int index, const float* raw) noexcept {
  const auto i = static_cast<std::size_t>(index);
  writeTerm(layout_.terms[i], layout_.clip, raw, frame_.data() + offset_[i]);
}

bool ObservationAssembler::commit() noexcept {
  for (const float v : frame_) {
    if (!std::isfinite(v)) return false;  // a non-finite frame never enters the history
  }
  const std::size_t n = frame_.size();
  if (empty_) {
    for (std::size_t h = 0; h < stacked_.size(); h += n) std::copy(frame_.begin(), frame_.end(), stacked_.begin() + static_cast<std::ptrdiff_t>(h));
    empty_ = false;
  } else {
    std::copy_backward(stacked_.begin(), stacked_.end() - static_cast<std::ptrdiff_t>(n), stacked_.end());
    std::copy(frame_.begin(), frame_.end(), stacked_.begin());
  }
  return true;
}

void ObservationAssembler::reset() noexcept { empty_ = true; }

}  // namespace pmg::policy
