#pragma once
/// @file observation.hpp
/// Builds the actor input from named observation terms, with scaling, clipping and history.
///
/// Setup: construct from the contract's ObservationLayout and look up each term once with
/// termIndex() (may throw). Loop (noexcept, allocation-free): setTerm() for every term, then
/// commit() shifts the history and returns whether every value was finite. data() is the actor
/// input, history_length frames, newest first: [frame_t, frame_{t-1}, ...].

#include <cstddef>
#include <string>
#include <vector>

#include "pmg/policy/contract.hpp"

namespace pmg::policy {

class ObservationAssembler {
 public:
  explicit ObservationAssembler(ObservationLayout layout);

  /// Index of a term by name, for setTerm(). @throws std::invalid_argument listing the
  /// contract's terms if `name` is not one of them.
  int termIndex(const std::string& name) const;
  /// Number of raw values term `index` expects.
  int termSize(int index) const noexcept;

  /// Writes term `index` of the current frame: value_k = clamp(raw[k] * scale_k, ±clip).
  /// @param raw (termSize(index) x 1) raw values in SI units. A NaN stays NaN (commit() reports it).
  void setTerm(int index, const double* raw) noexcept;
  /// Float overload of setTerm.
  void setTerm(int index, const float* raw) noexcept;

  /// Ends the current frame: shifts the history (on the first commit after reset() every
  /// history slot is filled with this frame). @return false if any value of the frame is not
  /// finite (the caller must not run the actor on it).
  bool commit() noexcept;
  /// Forgets the history (next commit() fills all slots). Call when the actor (re)starts.
  void reset() noexcept;

  /// Actor input, (size() x 1), valid after commit().
  const float* data() const noexcept { return stacked_.data(); }
  int size() const noexcept { return static_cast<int>(stacked_.size()); }
  const ObservationLayout& layout() const noexcept { return layout_; }

 private:
  ObservationLayout layout_;
  std::vector<int> offset_;     // start of each term in a frame
  std::vector<float> frame_;    // current frame being written
  std::vector<float> stacked_;  // history, newest first
  bool empty_ = true;
};

}  // namespace pmg::policy
