#include "ladar_perception/sim/world.h"

#include <algorithm>
#include <cmath>

#include "ladar_perception/io/image.h"

namespace ladar_perception {
namespace sim {

bool isGroundClass(SurfaceClass c) {
  return c == SurfaceClass::kRoad || c == SurfaceClass::kSidewalk || c == SurfaceClass::kTerrain;
}

bool isObstacleClass(SurfaceClass c) {
  switch (c) {
    case SurfaceClass::kCurb:
    case SurfaceClass::kCar:
    case SurfaceClass::kWall:
    case SurfaceClass::kPole:
    case SurfaceClass::kPerson:
    case SurfaceClass::kPothole:
      return true;
    default:
      return false;
  }
}

const char* className(SurfaceClass c) {
  switch (c) {
    case SurfaceClass::kRoad: return "road";
    case SurfaceClass::kSidewalk: return "sidewalk";
    case SurfaceClass::kTerrain: return "terrain";
    case SurfaceClass::kCurb: return "curb";
    case SurfaceClass::kCar: return "car";
    case SurfaceClass::kWall: return "wall";
    case SurfaceClass::kPole: return "pole";
    case SurfaceClass::kPerson: return "person";
    case SurfaceClass::kPothole: return "pothole";
    case SurfaceClass::kNone: return "none";
  }
  return "none";
}

bool classFromName(const std::string& name, SurfaceClass* c) {
  for (int k = 0; k < kNumSurfaceClasses; ++k) {
    if (name == className(static_cast<SurfaceClass>(k))) {
      *c = static_cast<SurfaceClass>(k);
      return true;
    }
  }
  if (name == "none") {
    *c = SurfaceClass::kNone;
    return true;
  }
  return false;
}

void classColor(SurfaceClass c, uint8_t rgb[3]) {
  static const uint8_t kPalette[kNumSurfaceClasses][3] = {
      {90, 90, 95},     // road: asphalt gray
      {190, 180, 165},  // sidewalk: light concrete
      {110, 150, 70},   // terrain: grass green
      {240, 200, 40},   // curb: yellow
      {200, 40, 40},    // car: red
      {120, 70, 40},    // wall: brown
      {20, 90, 20},     // pole/tree: dark green
      {240, 60, 220},   // person: magenta
      {20, 20, 120},    // pothole: dark blue
  };
  const int k = static_cast<int>(c);
  if (k < kNumSurfaceClasses) {
    rgb[0] = kPalette[k][0]; rgb[1] = kPalette[k][1]; rgb[2] = kPalette[k][2];
  } else {
    rgb[0] = rgb[1] = rgb[2] = 0;
  }
}

bool World::reset(double origin_x, double origin_y, double resolution, int nx, int ny,
                  float fill_height, SurfaceClass fill_class, std::string* error) {
  if (!(resolution > 0.0) || nx <= 0 || ny <= 0 || !std::isfinite(origin_x) ||
      !std::isfinite(origin_y) || static_cast<double>(nx) * ny > 4.0e8) {
    if (error) *error = "world grid needs a positive resolution and 1..4e8 cells";
    return false;
  }
  origin_x_ = origin_x;
  origin_y_ = origin_y;
  resolution_ = resolution;
  nx_ = nx;
  ny_ = ny;
  heights_.assign(static_cast<std::size_t>(nx) * ny, fill_height);
  classes_.assign(heights_.size(), static_cast<uint8_t>(fill_class));
  pyramid_.clear();
  level_w_.clear();
  drive_ = Trajectory();
  return true;
}

bool World::contains(double x, double y) const {
  return x >= origin_x_ && y >= origin_y_ && x < maxX() && y < maxY();
}

int World::cellX(double x) const {
  return static_cast<int>(std::floor((x - origin_x_) / resolution_));
}

int World::cellY(double y) const {
  return static_cast<int>(std::floor((y - origin_y_) / resolution_));
}

float World::height(double x, double y) const {
  const int ix = cellX(x), iy = cellY(y);
  if (!validCell(ix, iy)) return std::numeric_limits<float>::quiet_NaN();
  return heights_[index(ix, iy)];
}

SurfaceClass World::surfaceClass(double x, double y) const {
  const int ix = cellX(x), iy = cellY(y);
  if (!validCell(ix, iy)) return SurfaceClass::kNone;
  return static_cast<SurfaceClass>(classes_[index(ix, iy)]);
}

float World::smoothHeight(double x, double y) const {
  if (empty()) return std::numeric_limits<float>::quiet_NaN();
  const double u = (x - origin_x_) / resolution_ - 0.5;
  const double v = (y - origin_y_) / resolution_ - 0.5;
  const int i0 = static_cast<int>(std::floor(u)), j0 = static_cast<int>(std::floor(v));
  const double fu = u - i0, fv = v - j0;
  auto at = [&](int i, int j) {
    i = std::clamp(i, 0, nx_ - 1);
    j = std::clamp(j, 0, ny_ - 1);
    return static_cast<double>(heights_[index(i, j)]);
  };
  if (!contains(x, y)) return std::numeric_limits<float>::quiet_NaN();
  const double h = (1 - fu) * (1 - fv) * at(i0, j0) + fu * (1 - fv) * at(i0 + 1, j0) +
                   (1 - fu) * fv * at(i0, j0 + 1) + fu * fv * at(i0 + 1, j0 + 1);
  return static_cast<float>(h);
}

void World::finalize() {
  pyramid_.clear();
  level_w_.clear();
  if (empty()) return;
  max_height_ = *std::max_element(heights_.begin(), heights_.end());
  min_height_ = *std::min_element(heights_.begin(), heights_.end());
  // Level L holds the max of 2^L x 2^L blocks. Stop at 2^8 = 256 cells (25.6 m at 0.1 m): the
  // ray caster starts at the top level, so deeper pyramids only add descents.
  pyramid_.emplace_back();
  level_w_.push_back(nx_);
  int w = nx_, h = ny_;
  const std::vector<float>* prev = &heights_;
  for (int level = 1; level <= 8 && (w > 1 || h > 1); ++level) {
    const int w2 = (w + 1) / 2, h2 = (h + 1) / 2;
    std::vector<float> next(static_cast<std::size_t>(w2) * h2);
    for (int j = 0; j < h2; ++j) {
      for (int i = 0; i < w2; ++i) {
        float m = -std::numeric_limits<float>::infinity();
        for (int dj = 0; dj < 2; ++dj) {
          for (int di = 0; di < 2; ++di) {
            const int a = 2 * i + di, b = 2 * j + dj;
            if (a < w && b < h) m = std::max(m, (*prev)[static_cast<std::size_t>(b) * w + a]);
          }
        }
        next[static_cast<std::size_t>(j) * w2 + i] = m;
      }
    }
    pyramid_.push_back(std::move(next));
    level_w_.push_back(w2);
    prev = &pyramid_.back();
    w = w2;
    h = h2;
  }
}

Eigen::Isometry3d World::vehiclePose(double x, double y, double yaw) const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double half_length = 1.4, half_width = 0.8;
  auto ground = [&](double ax, double ay) {
    const float h = smoothHeight(x + ax * c - ay * s, y + ax * s + ay * c);
    return std::isfinite(h) ? static_cast<double>(h) : 0.0;
  };
  const double front = ground(half_length, 0), rear = ground(-half_length, 0);
  const double left = ground(0, half_width), right = ground(0, -half_width);
  // ROS conventions: positive pitch is nose down, positive roll is left side up.
  const double pitch = std::atan2(rear - front, 2 * half_length);
  const double roll = std::atan2(left - right, 2 * half_width);
  float z = height(x, y);
  if (!std::isfinite(z)) z = 0.f;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, z);
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  return pose;
}

Eigen::Isometry3d World::drivePose(double t) const {
  double x = 0, y = 0, yaw = 0;
  if (!drive_.empty()) drive_.pose2d(t, &x, &y, &yaw);
  return vehiclePose(x, y, yaw);
}

bool World::fromImage(const std::string& height_image, const std::string& class_image,
                      const ImageWorldOptions& options, World* out, std::string* error) {
  if (!(options.metres_per_pixel > 0.0) || !std::isfinite(options.height_scale)) {
    if (error) *error = "image world needs metres_per_pixel > 0 and a finite height_scale";
    return false;
  }
  GrayImage heights;
  std::string err;
  if (!readImage(height_image, &heights, &err)) {
    if (error) *error = "height image: " + err;
    return false;
  }
  GrayImage classes;
  const bool has_classes = !class_image.empty();
  if (has_classes) {
    if (!readImage(class_image, &classes, &err)) {
      if (error) *error = "class image: " + err;
      return false;
    }
    if (classes.width != heights.width || classes.height != heights.height) {
      if (error) *error = "class image size differs from the height image";
      return false;
    }
  }
  const int nx = heights.width, ny = heights.height;
  const double res = options.metres_per_pixel;
  if (!out->reset(options.centre_x - 0.5 * nx * res, options.centre_y - 0.5 * ny * res, res, nx,
                  ny, 0.f, SurfaceClass::kTerrain, error)) {
    return false;
  }
  float lowest = std::numeric_limits<float>::infinity();
  for (int row = 0; row < ny; ++row) {
    for (int col = 0; col < nx; ++col) {
      const float v = heights.value[static_cast<std::size_t>(row) * nx + col];
      // Thesis 4.2.1: black = height_scale, white = 0.
      const float h = static_cast<float>(options.height_scale * (1.0 - v));
      out->heights_[out->index(col, ny - 1 - row)] = h;  // top row is north
      lowest = std::min(lowest, h);
    }
  }
  uint8_t palette[kNumSurfaceClasses][3];
  for (int k = 0; k < kNumSurfaceClasses; ++k) classColor(static_cast<SurfaceClass>(k), palette[k]);
  for (int row = 0; row < ny; ++row) {
    for (int col = 0; col < nx; ++col) {
      const std::size_t pix = static_cast<std::size_t>(row) * nx + col;
      const std::size_t cell = out->index(col, ny - 1 - row);
      SurfaceClass c = SurfaceClass::kTerrain;
      if (!has_classes) {
        if (out->heights_[cell] - lowest > options.obstacle_height) c = SurfaceClass::kWall;
      } else if (classes.rgb.empty()) {
        // Gray class image: the 8-bit value is the class code.
        const int code = static_cast<int>(std::lround(classes.value[pix] * 255.0));
        if (code >= kNumSurfaceClasses) {
          if (error) *error = "class image holds code " + std::to_string(code) +
                              ", valid codes are 0.." + std::to_string(kNumSurfaceClasses - 1);
          return false;
        }
        c = static_cast<SurfaceClass>(code);
      } else {
        // Colour class image: the nearest palette colour.
        int best = 0;
        long best_d = -1;
        for (int k = 0; k < kNumSurfaceClasses; ++k) {
          long d = 0;
          for (int ch = 0; ch < 3; ++ch) {
            const long diff = static_cast<long>(classes.rgb[3 * pix + ch]) - palette[k][ch];
            d += diff * diff;
          }
          if (best_d < 0 || d < best_d) { best_d = d; best = k; }
        }
        c = static_cast<SurfaceClass>(best);
      }
      out->classes_[cell] = static_cast<uint8_t>(c);
    }
  }
  out->setName(height_image);
  out->finalize();
  return true;
}

}  // namespace sim
}  // namespace ladar_perception
