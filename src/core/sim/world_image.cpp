#include "ladar_perception/sim/world_image.h"

#include <algorithm>
#include <cmath>

namespace ladar_perception {
namespace sim {

namespace {

struct Canvas {
  RgbImage* image;
  const World* world;
  int k;  // cells per pixel

  // World (x, y) -> pixel (column, row); north up.
  Eigen::Vector2d pixel(double x, double y) const {
    const double u = (x - world->originX()) / world->resolution() / k;
    const double v = (y - world->originY()) / world->resolution() / k;
    return Eigen::Vector2d(u, image->height - v);
  }
  void dot(const Eigen::Vector2d& p, int radius, uint8_t r, uint8_t g, uint8_t b) {
    const int cx = static_cast<int>(std::floor(p.x())), cy = static_cast<int>(std::floor(p.y()));
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx)
        if (dx * dx + dy * dy <= radius * radius) image->set(cx + dx, cy + dy, r, g, b);
  }
  void line(const Eigen::Vector2d& a, const Eigen::Vector2d& b, int radius, uint8_t r, uint8_t g,
            uint8_t bl) {
    const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm())));
    for (int s = 0; s <= steps; ++s) dot(a + (b - a) * (static_cast<double>(s) / steps), radius, r, g, bl);
  }
};

}  // namespace

RgbImage renderTopDown(const World& world, const std::vector<Eigen::Vector2d>& path,
                       const std::vector<Eigen::Isometry3d>& poses, const TopDownOptions& options) {
  if (world.empty()) return RgbImage(1, 1);
  const int longest = std::max(world.cellsX(), world.cellsY());
  const int k = std::max(1, (longest + std::max(1, options.max_pixels) - 1) / std::max(1, options.max_pixels));
  const int w = (world.cellsX() + k - 1) / k, h = (world.cellsY() + k - 1) / k;
  RgbImage image(w, h);
  // The highest cell of each pixel's block decides its class, so thin obstacles stay visible.
  std::vector<float> top(static_cast<std::size_t>(w) * h, -1e30f);
  std::vector<uint8_t> cls(top.size(), static_cast<uint8_t>(SurfaceClass::kNone));
  for (int iy = 0; iy < world.cellsY(); ++iy) {
    for (int ix = 0; ix < world.cellsX(); ++ix) {
      const std::size_t p = static_cast<std::size_t>(iy / k) * w + ix / k;
      const float z = world.cellHeight(ix, iy);
      const uint8_t c = static_cast<uint8_t>(world.cellClass(ix, iy));
      // Obstacles win over ground within a pixel; otherwise the highest cell.
      const bool obstacle = isObstacleClass(static_cast<SurfaceClass>(c));
      const bool had_obstacle = isObstacleClass(static_cast<SurfaceClass>(cls[p]));
      if ((obstacle && !had_obstacle) || (obstacle == had_obstacle && z > top[p])) {
        top[p] = z;
        cls[p] = c;
      }
    }
  }
  const double pixel_m = world.resolution() * k;
  for (int py = 0; py < h; ++py) {
    for (int px = 0; px < w; ++px) {
      const std::size_t p = static_cast<std::size_t>(py) * w + px;
      uint8_t rgb[3];
      classColor(static_cast<SurfaceClass>(cls[p]), rgb);
      double shade = 1.0;
      if (options.hillshade && px + 1 < w && py + 1 < h) {
        const double gx = (top[p + 1] - top[p]) / pixel_m;
        const double gy = (top[p + w] - top[p]) / pixel_m;  // +row is south
        shade = std::clamp(1.0 - 1.5 * gx + 1.5 * gy, 0.45, 1.35);
      }
      const int row = h - 1 - py;  // north up
      image.set(px, row, static_cast<uint8_t>(std::min(255.0, rgb[0] * shade)),
                static_cast<uint8_t>(std::min(255.0, rgb[1] * shade)),
                static_cast<uint8_t>(std::min(255.0, rgb[2] * shade)));
    }
  }
  Canvas canvas{&image, &world, k};
  const int thick = std::max(1, static_cast<int>(std::lround(0.3 / pixel_m)));
  for (std::size_t s = 1; s < path.size(); ++s) {
    canvas.line(canvas.pixel(path[s - 1].x(), path[s - 1].y()), canvas.pixel(path[s].x(), path[s].y()),
                thick, 255, 255, 255);
  }
  const int marker = std::max(3, static_cast<int>(std::lround(1.2 / pixel_m)));
  if (!path.empty()) {
    canvas.dot(canvas.pixel(path.front().x(), path.front().y()), marker, 40, 220, 40);
    canvas.dot(canvas.pixel(path.back().x(), path.back().y()), marker, 230, 30, 30);
  }
  for (const Eigen::Isometry3d& pose : poses) {
    const Eigen::Vector3d a = pose.translation();
    const Eigen::Vector3d b = pose * Eigen::Vector3d(2.5, 0, 0);
    canvas.line(canvas.pixel(a.x(), a.y()), canvas.pixel(b.x(), b.y()), thick, 250, 230, 0);
    canvas.dot(canvas.pixel(a.x(), a.y()), std::max(2, marker / 2), 250, 230, 0);
  }
  return image;
}

}  // namespace sim
}  // namespace ladar_perception
