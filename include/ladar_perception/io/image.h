// Small image I/O for people-facing pictures (PNG out) and simulator worlds (PGM/PNG in).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ladar_perception {

// 8-bit RGB, row-major, top row first.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  // 3 * width * height

  RgbImage() = default;
  RgbImage(int w, int h, uint8_t r = 0, uint8_t g = 0, uint8_t b = 0);
  void set(int x, int y, uint8_t r, uint8_t g, uint8_t b) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    uint8_t* p = &rgb[3 * (static_cast<std::size_t>(y) * width + x)];
    p[0] = r; p[1] = g; p[2] = b;
  }
};

// One channel image normalised to [0, 1] (8- or 16-bit sources), row-major, top row first.
// RGB sources are converted to luminance; `rgb` keeps the original colours when present (used
// by class images).
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<float> value;   // width * height, 0 = black, 1 = white
  std::vector<uint8_t> rgb;   // 3 * width * height, empty for gray sources
};

bool writePng(const std::string& path, const RgbImage& image, std::string* error);

// Reads PNG (gray, gray+alpha, RGB, RGBA, palette; 8 or 16 bit) or binary/ASCII PGM (P2/P5).
bool readImage(const std::string& path, GrayImage* image, std::string* error);

}  // namespace ladar_perception
