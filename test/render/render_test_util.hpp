#pragma once
// Helpers shared by the render tests: synthetic PMG_STATE event logs and image statistics.
#include <string>
#include <vector>

#include "pmg/render/image.hpp"
#include "pmg/render/state_track.hpp"

namespace pmg::render::test {

/// Writes an LCM event log with one PMG_STATE message per sample (num_joints = sample.q.size(),
/// unless @p num_joints_override ≥ 0) and, before each, one message on channel "OTHER".
void writeStateLog(const std::string& path, const std::vector<StateSample>& samples, int num_joints_override = -1);

/// A fresh, empty temporary folder for one test of this process (removed first if it exists, and
/// again when the process exits).
std::string tempDir(const std::string& name);

/// Standard deviation of the pixel luminance (0.299 r + 0.587 g + 0.114 b) [0..255].
double luminanceStdDev(const Image& image);

/// Pixels whose r, g or b differs by more than @p tolerance between @p a and @p b (same size).
struct Difference {
  long count = 0;              ///< number of differing pixels
  double centroid_x = 0.0;     ///< mean x of the differing pixels [px] (0 if none)
  double centroid_y = 0.0;     ///< mean y of the differing pixels [px], 0 = top row
  int min_x = 0, max_x = -1, min_y = 0, max_y = -1;  ///< bounding box of the differing pixels
};
Difference difference(const Image& a, const Image& b, int tolerance = 8);

/// A private Xvfb X server for tests on machines without a display (CI). start() launches
/// `Xvfb -displayfd` (the server picks a free display number) and sets $DISPLAY for this process;
/// the destructor stops the server and restores $DISPLAY.
class ScopedXvfb {
 public:
  ScopedXvfb() = default;
  ~ScopedXvfb();
  ScopedXvfb(const ScopedXvfb&) = delete;
  ScopedXvfb& operator=(const ScopedXvfb&) = delete;
  /// @return "" on success, else why the server could not be started (e.g. Xvfb not installed).
  std::string start();

 private:
  int pid_ = -1;
};

}  // namespace pmg::render::test
