#include "ladar_perception/io/image.h"

#include <png.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

namespace ladar_perception {

RgbImage::RgbImage(int w, int h, uint8_t r, uint8_t g, uint8_t b)
    : width(w), height(h), rgb(3 * static_cast<std::size_t>(w) * h) {
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = r; rgb[i + 1] = g; rgb[i + 2] = b;
  }
}

namespace {
struct FileCloser {
  void operator()(FILE* f) const { if (f) std::fclose(f); }
};
using FilePtr = std::unique_ptr<FILE, FileCloser>;
}  // namespace

bool writePng(const std::string& path, const RgbImage& image, std::string* error) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * static_cast<std::size_t>(image.width) * image.height) {
    if (error) *error = "image has no pixels or an inconsistent size";
    return false;
  }
  FilePtr f(std::fopen(path.c_str(), "wb"));
  if (!f) {
    if (error) *error = "cannot open " + path + " for writing";
    return false;
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    if (error) *error = "libpng could not be initialised";
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    if (error) *error = "libpng failed while writing " + path;
    return false;
  }
  png_init_io(png, f.get());
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) {
    png_write_row(png, const_cast<png_bytep>(&image.rgb[3 * static_cast<std::size_t>(y) * image.width]));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

namespace {

bool readPng(const std::string& path, GrayImage* image, std::string* error) {
  FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) {
    if (error) *error = "cannot open " + path;
    return false;
  }
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(&png, &info, nullptr);
    if (error) *error = "libpng could not be initialised";
    return false;
  }
  // Everything that owns memory lives outside the setjmp scope: libpng's error handler
  // longjmps back here and skips the destructors of anything declared after it.
  std::vector<uint8_t> buffer;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    if (error) *error = path + " is not a readable PNG";
    return false;
  }
  png_init_io(png, f.get());
  png_read_info(png, info);
  const png_uint_32 w = png_get_image_width(png, info);
  const png_uint_32 h = png_get_image_height(png, info);
  if (w == 0 || h == 0 || w > 20000 || h > 20000) {
    png_destroy_read_struct(&png, &info, nullptr);
    if (error) *error = path + ": image size out of range (1..20000 pixels per side)";
    return false;
  }
  const int bit_depth = png_get_bit_depth(png, info);
  const int color_type = png_get_color_type(png, info);
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  png_set_strip_alpha(png);
  if (bit_depth == 16) png_set_swap(png);  // little-endian 16-bit samples
  png_read_update_info(png, info);
  const int channels = png_get_channels(png, info);
  const int depth = png_get_bit_depth(png, info);
  const std::size_t row_bytes = png_get_rowbytes(png, info);
  buffer.resize(row_bytes * h);
  rows.resize(h);
  for (png_uint_32 y = 0; y < h; ++y) rows[y] = &buffer[y * row_bytes];
  png_read_image(png, rows.data());
  png_destroy_read_struct(&png, &info, nullptr);

  image->width = static_cast<int>(w);
  image->height = static_cast<int>(h);
  image->value.assign(static_cast<std::size_t>(w) * h, 0.f);
  image->rgb.clear();
  if (channels >= 3) image->rgb.resize(3 * static_cast<std::size_t>(w) * h);
  const float scale = depth == 16 ? 1.f / 65535.f : 1.f / 255.f;
  for (png_uint_32 y = 0; y < h; ++y) {
    for (png_uint_32 x = 0; x < w; ++x) {
      float c[3];
      for (int k = 0; k < std::min(channels, 3); ++k) {
        const std::size_t idx = (static_cast<std::size_t>(x) * channels + k) * (depth / 8);
        const uint8_t* p = rows[y] + idx;
        c[k] = depth == 16 ? static_cast<float>(p[0] | (p[1] << 8)) * scale : p[0] * scale;
      }
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (channels >= 3) {
        image->value[i] = 0.299f * c[0] + 0.587f * c[1] + 0.114f * c[2];
        for (int k = 0; k < 3; ++k) image->rgb[3 * i + k] = static_cast<uint8_t>(c[k] * 255.f + 0.5f);
      } else {
        image->value[i] = c[0];
      }
    }
  }
  return true;
}

bool readPgm(const std::string& path, GrayImage* image, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (error) *error = "cannot open " + path;
    return false;
  }
  auto next_token = [&in](std::string* tok) {
    tok->clear();
    char c;
    while (in.get(c)) {
      if (c == '#') {
        std::string comment;
        std::getline(in, comment);
        continue;
      }
      if (std::isspace(static_cast<unsigned char>(c))) {
        if (!tok->empty()) return true;
        continue;
      }
      tok->push_back(c);
    }
    return !tok->empty();
  };
  std::string magic, sw, sh, smax;
  if (!next_token(&magic) || (magic != "P2" && magic != "P5") || !next_token(&sw) ||
      !next_token(&sh) || !next_token(&smax)) {
    if (error) *error = path + " is not a PGM (P2/P5) file";
    return false;
  }
  long w = 0, h = 0, maxval = 0;
  try {
    w = std::stol(sw); h = std::stol(sh); maxval = std::stol(smax);
  } catch (...) {
    w = 0;
  }
  if (w <= 0 || h <= 0 || w > 20000 || h > 20000 || maxval <= 0 || maxval > 65535) {
    if (error) *error = path + ": PGM header out of range";
    return false;
  }
  image->width = static_cast<int>(w);
  image->height = static_cast<int>(h);
  image->rgb.clear();
  image->value.assign(static_cast<std::size_t>(w) * h, 0.f);
  const float scale = 1.f / static_cast<float>(maxval);
  if (magic == "P5") {
    const int bytes = maxval > 255 ? 2 : 1;
    std::vector<uint8_t> raw(static_cast<std::size_t>(w) * h * bytes);
    in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size()));
    if (static_cast<std::size_t>(in.gcount()) != raw.size()) {
      if (error) *error = path + ": PGM pixel data is truncated";
      return false;
    }
    for (std::size_t i = 0; i < image->value.size(); ++i) {
      const unsigned v = bytes == 2 ? (raw[2 * i] << 8) | raw[2 * i + 1] : raw[i];  // big-endian
      image->value[i] = std::min(1.f, static_cast<float>(v) * scale);
    }
  } else {
    std::string tok;
    for (std::size_t i = 0; i < image->value.size(); ++i) {
      if (!next_token(&tok)) {
        if (error) *error = path + ": PGM pixel data is truncated";
        return false;
      }
      long v = 0;
      try { v = std::stol(tok); } catch (...) { v = -1; }
      if (v < 0) {
        if (error) *error = path + ": PGM pixel value is not a number";
        return false;
      }
      image->value[i] = std::min(1.f, static_cast<float>(v) * scale);
    }
  }
  return true;
}

}  // namespace

bool readImage(const std::string& path, GrayImage* image, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (error) *error = "cannot open " + path;
    return false;
  }
  char magic[8] = {0};
  in.read(magic, 8);
  in.close();
  static const unsigned char kPngSig[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  if (std::equal(kPngSig, kPngSig + 8, reinterpret_cast<unsigned char*>(magic))) {
    return readPng(path, image, error);
  }
  if (magic[0] == 'P' && (magic[1] == '2' || magic[1] == '5')) return readPgm(path, image, error);
  if (error) *error = path + " is neither PNG nor PGM";
  return false;
}

}  // namespace ladar_perception
