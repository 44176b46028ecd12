#include "ladar_perception/calibration/nearest_grid.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ladar_perception {
namespace calibration {

namespace {
constexpr int32_t kCellRange = 1 << 20;  // cell coordinates within +-2^20 (+-524 km at 0.5 m)

// splitmix64's finaliser: every bit of the key reaches the low bits the table is indexed by.
inline uint64_t hashKey(int64_t key) {
  uint64_t h = static_cast<uint64_t>(key);
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ULL;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBULL;
  return h ^ (h >> 31);
}
}  // namespace

inline int64_t NearestGrid::keyOf(int32_t ix, int32_t iy, int32_t iz) {
  return (static_cast<int64_t>(ix + kCellRange) << 42) |
         (static_cast<int64_t>(iy + kCellRange) << 21) | static_cast<int64_t>(iz + kCellRange);
}

inline int NearestGrid::cellIndex(int64_t key) const {
  if (slots_.empty()) return -1;
  for (uint64_t s = hashKey(key) & mask_;; s = (s + 1) & mask_) {
    const int32_t c = slots_[s];
    if (c < 0) return -1;
    if (cells_[c].key == key) return c;
  }
}

void NearestGrid::build(const std::vector<Eigen::Vector3f>& points, float cell) {
  cell_ = cell > 0 ? cell : 1.0f;
  inv_cell_ = 1.0f / cell_;
  points_.clear();
  original_.clear();
  cells_.clear();
  slots_.clear();
  std::vector<std::pair<int64_t, int>> keyed;
  keyed.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f c = (points[i] * inv_cell_).array().floor();
    if (!c.allFinite() || (c.array().abs() >= static_cast<float>(kCellRange - 2)).any()) continue;
    keyed.emplace_back(keyOf(static_cast<int32_t>(c.x()), static_cast<int32_t>(c.y()),
                             static_cast<int32_t>(c.z())),
                       static_cast<int>(i));
  }
  std::sort(keyed.begin(), keyed.end());
  points_.reserve(keyed.size());
  original_.reserve(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first) {
      Cell cl;
      cl.key = keyed[i].first;
      cl.begin = cl.end = static_cast<uint32_t>(i);
      cells_.push_back(cl);
    }
    ++cells_.back().end;
    points_.push_back(points[keyed[i].second]);
    original_.push_back(keyed[i].second);
  }
  if (cells_.empty()) return;
  std::size_t size = 16;
  while (size < 2 * cells_.size()) size *= 2;
  slots_.assign(size, -1);
  mask_ = size - 1;
  for (std::size_t c = 0; c < cells_.size(); ++c) {
    uint64_t s = hashKey(cells_[c].key) & mask_;
    while (slots_[s] >= 0) s = (s + 1) & mask_;
    slots_[s] = static_cast<int32_t>(c);
  }
}

int NearestGrid::nearest(const Eigen::Vector3f& query, float* sq_dist, float max_sq_dist) const {
  if (sq_dist) *sq_dist = max_sq_dist;
  const float cell2 = cell_ * cell_;
  if (cells_.empty()) return max_sq_dist <= cell2 ? -1 : kUndecided;
  const Eigen::Vector3f f = (query * inv_cell_).array().floor();
  if (!f.allFinite() || (f.array().abs() >= static_cast<float>(kCellRange - 2)).any()) {
    return kUndecided;
  }
  const int32_t qx = static_cast<int32_t>(f.x()), qy = static_cast<int32_t>(f.y()),
                qz = static_cast<int32_t>(f.z());
  // Squared gaps from the query to its cell's lower and upper faces, per axis: a neighbour
  // cell can hold a closer point only when the sum of its offsets' gaps is below the best.
  float gap2[3][3];
  for (int a = 0; a < 3; ++a) {
    const float lo = query[a] - f[a] * cell_, hi = cell_ - lo;
    gap2[a][0] = lo * lo;
    gap2[a][1] = 0.0f;
    gap2[a][2] = hi * hi;
  }
  float best_d2 = max_sq_dist;
  int best = -1;
  const auto scanCell = [&](int32_t ix, int32_t iy, int32_t iz) {
    const int c = cellIndex(keyOf(ix, iy, iz));
    if (c < 0) return;
    for (uint32_t i = cells_[c].begin; i < cells_[c].end; ++i) {
      const float d2 = (points_[i] - query).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best = static_cast<int>(i);
      }
    }
  };
  scanCell(qx, qy, qz);  // the query's own cell first: its best bounds the others
  static constexpr int kOrder[3] = {1, 0, 2};  // offsets 0, -1, +1 as gap2 columns
  for (int ax : kOrder) {
    const float gx = gap2[0][ax];
    if (gx >= best_d2) continue;
    for (int ay : kOrder) {
      const float gxy = gx + gap2[1][ay];
      if (gxy >= best_d2) continue;
      for (int az : kOrder) {
        if (ax == 1 && ay == 1 && az == 1) continue;
        if (gxy + gap2[2][az] >= best_d2) continue;
        scanCell(qx + ax - 1, qy + ay - 1, qz + az - 1);
      }
    }
  }
  // Every point within one cell size of the query lies in the 27 cells considered.
  if (best >= 0 && best_d2 <= cell2) {
    if (sq_dist) *sq_dist = best_d2;
    return original_[best];
  }
  return max_sq_dist <= cell2 ? -1 : kUndecided;
}

}  // namespace calibration
}  // namespace ladar_perception
