#include "ladar_perception/eval/phantom_holes.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ladar_perception {
namespace eval {
namespace {

float median(std::vector<float>* v) {
  if (v->empty()) return std::numeric_limits<float>::quiet_NaN();
  const std::size_t mid = v->size() / 2;
  std::nth_element(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(mid), v->end());
  return (*v)[mid];
}

// A square grid of cells of `size` metres centred on the sensor, covering +-extent.
struct Grid {
  float size;
  int half, width;
  Grid(float cell, float extent) : size(cell), half(static_cast<int>(std::ceil(extent / cell)) + 1), width(2 * half + 1) {}
  bool index(float x, float y, int* ix, int* iy) const {
    *ix = static_cast<int>(std::floor(x / size)) + half;
    *iy = static_cast<int>(std::floor(y / size)) + half;
    return *ix >= 0 && *iy >= 0 && *ix < width && *iy < width;
  }
  std::size_t at(int ix, int iy) const { return static_cast<std::size_t>(iy) * width + ix; }
  std::size_t cells() const { return static_cast<std::size_t>(width) * width; }
};

}  // namespace

std::size_t findPhantomHoles(const PointCloudView& view, const GroundClassification& result,
                             const PhantomHoleParams& params,
                             std::vector<PhantomHole>* phantoms) {
  phantoms->clear();
  const std::size_t n = std::min(view.size(), result.size());
  const float reach = params.max_range + 2.f * params.ground_cell;
  // Local ground: the median height of the ground returns per cell, then the lowest of the
  // 3 x 3 cell medians around a return (a return is below the ground only when it is below all
  // of it: the road at the foot of a curb is not below the sidewalk's ground).
  const Grid ground(params.ground_cell, reach);
  std::vector<std::vector<float>> heights(ground.cells());
  std::vector<Eigen::Vector3f> p(n);
  std::vector<uint8_t> near(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    p[i] = view.xyz(i);
    if (!p[i].allFinite()) continue;
    const float r = p[i].head<2>().norm();
    if (r > reach) continue;
    near[i] = r <= params.max_range;
    int ix, iy;
    if (result.labels[i] == kLabelGround && ground.index(p[i].x(), p[i].y(), &ix, &iy)) {
      heights[ground.at(ix, iy)].push_back(p[i].z());
    }
  }
  std::vector<float> cell_median(ground.cells());
  for (std::size_t c = 0; c < ground.cells(); ++c) cell_median[c] = median(&heights[c]);
  auto local_ground = [&](const Eigen::Vector3f& q) {
    int ix, iy;
    if (!ground.index(q.x(), q.y(), &ix, &iy)) return std::numeric_limits<float>::infinity();
    float lowest = std::numeric_limits<float>::infinity();
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = ix + dx, y = iy + dy;
        if (x < 0 || y < 0 || x >= ground.width || y >= ground.width) continue;
        const float m = cell_median[ground.at(x, y)];
        if (std::isfinite(m)) lowest = std::min(lowest, m);
      }
    }
    return lowest;
  };
  // Below-ground obstacle returns per cluster cell; obstacle returns standing above the ground.
  const Grid cells(params.cluster_cell, reach);
  std::vector<int> below_count(cells.cells(), 0);
  std::vector<float> below_depth(cells.cells(), 0.f);
  std::vector<uint8_t> object(cells.cells(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!near[i] || result.labels[i] != kLabelObstacle) continue;
    const float g = local_ground(p[i]);
    if (!std::isfinite(g)) continue;
    int ix, iy;
    if (!cells.index(p[i].x(), p[i].y(), &ix, &iy)) continue;
    const std::size_t c = cells.at(ix, iy);
    const float depth = g - p[i].z();
    if (depth > params.max_depth) continue;  // a multipath or reflection artefact
    if (depth > params.min_depth) {
      ++below_count[c];
      below_depth[c] = std::max(below_depth[c], depth);
    } else if (-depth > params.object_height) {
      object[c] = 1;
    }
  }
  // 8-connected clusters of below-ground cells.
  const int reach_cells = static_cast<int>(std::ceil(params.object_radius / params.cluster_cell));
  std::vector<uint8_t> seen(cells.cells(), 0);
  std::vector<std::pair<int, int>> stack, members;
  std::size_t clusters = 0;
  for (int y0 = 0; y0 < cells.width; ++y0) {
    for (int x0 = 0; x0 < cells.width; ++x0) {
      const std::size_t c0 = cells.at(x0, y0);
      if (!below_count[c0] || seen[c0]) continue;
      stack.assign(1, {x0, y0});
      seen[c0] = 1;
      members.clear();
      while (!stack.empty()) {
        const auto [x, y] = stack.back();
        stack.pop_back();
        members.emplace_back(x, y);
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= cells.width || ny >= cells.width) continue;
            const std::size_t c = cells.at(nx, ny);
            if (below_count[c] && !seen[c]) {
              seen[c] = 1;
              stack.emplace_back(nx, ny);
            }
          }
        }
      }
      PhantomHole hole;
      Eigen::Vector2f sum = Eigen::Vector2f::Zero();
      bool beside_object = false;
      for (const auto& [x, y] : members) {
        const std::size_t c = cells.at(x, y);
        hole.returns += below_count[c];
        hole.depth = std::max(hole.depth, below_depth[c]);
        sum += static_cast<float>(below_count[c]) *
               Eigen::Vector2f((x - cells.half + 0.5f) * cells.size, (y - cells.half + 0.5f) * cells.size);
        for (int dy = -reach_cells; dy <= reach_cells && !beside_object; ++dy) {
          for (int dx = -reach_cells; dx <= reach_cells; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= cells.width || ny >= cells.width) continue;
            if (object[cells.at(nx, ny)]) {
              beside_object = true;
              break;
            }
          }
        }
      }
      if (hole.returns < params.min_returns) continue;
      ++clusters;
      if (beside_object) continue;
      hole.centre = sum / static_cast<float>(hole.returns);
      phantoms->push_back(hole);
    }
  }
  return clusters;
}

}  // namespace eval
}  // namespace ladar_perception
