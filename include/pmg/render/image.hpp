#pragma once
/// @file image.hpp
/// 8-bit RGB images, side-by-side composition (frame strips) and PNG output through libpng.

#include <cstdint>
#include <string>
#include <vector>

namespace pmg::render {

/// An 8-bit RGB image, rows top to bottom, pixels left to right, 3 bytes (r, g, b) per pixel:
/// rgb.size() == 3 · width · height.
struct Image {
  int width = 0;   ///< [px]
  int height = 0;  ///< [px]
  std::vector<std::uint8_t> rgb;

  Image() = default;
  /// A width × height image filled with the colour (r, g, b).
  Image(int w, int h, std::uint8_t r = 0, std::uint8_t g = 0, std::uint8_t b = 0);
  std::uint8_t* pixel(int x, int y) { return rgb.data() + 3 * (static_cast<std::size_t>(y) * width + x); }
  const std::uint8_t* pixel(int x, int y) const {
    return rgb.data() + 3 * (static_cast<std::size_t>(y) * width + x);
  }
};

/// Places @p frames side by side, top-aligned, separated by @p gap px of colour @p gap_rgb
/// (3 bytes). Frames may differ in height (the strip takes the tallest; the rest is gap colour).
/// @throws std::invalid_argument if @p frames is empty, a frame is empty or gap < 0.
Image hstack(const std::vector<Image>& frames, int gap, const std::uint8_t gap_rgb[3]);

/// Writes @p image as an 8-bit RGB PNG file (libpng). @throws std::runtime_error naming @p path
/// and libpng's message if the file cannot be written, std::invalid_argument if the image is empty
/// or its buffer size is not 3 · width · height.
void writePng(const std::string& path, const Image& image);

/// Reads an 8-bit PNG file back as RGB (alpha dropped, grey expanded); used by tests and tools.
/// @throws std::runtime_error naming @p path and libpng's message.
Image readPng(const std::string& path);

}  // namespace pmg::render
