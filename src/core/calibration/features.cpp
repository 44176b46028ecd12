#include "ladar_perception/calibration/features.h"

#include <cmath>
#include <limits>

namespace ladar_perception {
namespace calibration {

void FeatureExtractor::extract(const PointVector& points, FeatureSet* out, int min_points) {
  out->clear();
  if (points.empty() || !(bin_ > 0)) return;
  const float inv = static_cast<float>(1.0 / bin_);
  // Grid over the bounding box of the points, in whole bins from the odom origin.
  int ix0 = std::numeric_limits<int>::max(), iy0 = ix0;
  int ix1 = std::numeric_limits<int>::min(), iy1 = ix1;
  for (const Eigen::Vector3f& p : points) {
    const int ix = static_cast<int>(std::floor(p.x() * inv));
    const int iy = static_cast<int>(std::floor(p.y() * inv));
    ix0 = std::min(ix0, ix);
    ix1 = std::max(ix1, ix);
    iy0 = std::min(iy0, iy);
    iy1 = std::max(iy1, iy);
  }
  const long nx = static_cast<long>(ix1) - ix0 + 1;
  const long ny = static_cast<long>(iy1) - iy0 + 1;
  if (nx <= 0 || ny <= 0 || nx * ny > 50'000'000L) return;  // absurd extent: refuse, no crash
  const std::size_t cells = static_cast<std::size_t>(nx * ny);
  max_index_.assign(cells, -1);
  min_index_.assign(cells, -1);
  count_.assign(cells, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    const long cx = static_cast<long>(std::floor(p.x() * inv)) - ix0;
    const long cy = static_cast<long>(std::floor(p.y() * inv)) - iy0;
    const std::size_t c = static_cast<std::size_t>(cy * nx + cx);
    const int32_t idx = static_cast<int32_t>(i);
    if (count_[c]++ == 0) {
      max_index_[c] = idx;
      min_index_[c] = idx;
    } else {
      if (p.z() > points[max_index_[c]].z()) max_index_[c] = idx;
      if (p.z() < points[min_index_[c]].z()) min_index_[c] = idx;
    }
  }
  for (std::size_t c = 0; c < cells; ++c) {
    if (count_[c] < std::max(1, min_points)) continue;
    out->maxima.push_back(points[max_index_[c]]);
    out->minima.push_back(points[min_index_[c]]);
  }
}

FeatureSet extractFeatures(const PointVector& points, double bin_size) {
  FeatureExtractor extractor(bin_size);
  FeatureSet out;
  extractor.extract(points, &out);
  return out;
}

}  // namespace calibration
}  // namespace ladar_perception
