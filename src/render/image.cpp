#include "pmg/render/image.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <png.h>

namespace pmg::render {

Image::Image(int w, int h, std::uint8_t r, std::uint8_t g, std::uint8_t b) : width(w), height(h) {
  if (w <= 0 || h <= 0) throw std::invalid_argument("Image: width and height must be > 0");
  rgb.resize(3 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = r;
    rgb[i + 1] = g;
    rgb[i + 2] = b;
  }
}

Image hstack(const std::vector<Image>& frames, int gap, const std::uint8_t gap_rgb[3]) {
  if (frames.empty()) throw std::invalid_argument("hstack: no frames");
  if (gap < 0) throw std::invalid_argument("hstack: gap must be >= 0");
  int width = gap * static_cast<int>(frames.size() - 1);
  int height = 0;
  for (const Image& f : frames) {
    if (f.width <= 0 || f.height <= 0 || f.rgb.size() != 3 * static_cast<std::size_t>(f.width) * f.height)
      throw std::invalid_argument("hstack: empty frame or buffer size != 3 * width * height");
    width += f.width;
    height = std::max(height, f.height);
  }
  Image strip(width, height, gap_rgb[0], gap_rgb[1], gap_rgb[2]);
  int x0 = 0;
  for (const Image& f : frames) {
    for (int y = 0; y < f.height; ++y) std::memcpy(strip.pixel(x0, y), f.pixel(0, y), 3 * static_cast<std::size_t>(f.width));
    x0 += f.width + gap;
  }
  return strip;
}

void writePng(const std::string& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * static_cast<std::size_t>(image.width) * image.height)
    throw std::invalid_argument(path + ": cannot write an empty image or one whose buffer size != 3 * width * height");
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGB;
  if (!png_image_write_to_file(&png, path.c_str(), 0, image.rgb.data(), 3 * image.width, nullptr)) {
    const std::string message = png.message;
    png_image_free(&png);
    throw std::runtime_error(path + ": cannot write PNG (libpng: " + message + ")");
  }
}

Image readPng(const std::string& path) {
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str()))
    throw std::runtime_error(path + ": cannot read PNG (libpng: " + std::string(png.message) + ")");
  png.format = PNG_FORMAT_RGB;
  Image image(static_cast<int>(png.width), static_cast<int>(png.height));
  if (!png_image_finish_read(&png, nullptr, image.rgb.data(), 3 * image.width, nullptr)) {
    const std::string message = png.message;
    png_image_free(&png);
    throw std::runtime_error(path + ": cannot decode PNG (libpng: " + message + ")");
  }
  return image;
}

}  // namespace pmg::render
