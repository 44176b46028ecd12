#include "ladar_perception/calibration/error_metrics.h"

#include <algorithm>
#include <cmath>

namespace ladar_perception {
namespace calibration {

double trimmedMean(std::vector<float>* d, double fraction) {
  if (d->empty()) return std::numeric_limits<double>::infinity();
  fraction = std::min(1.0, std::max(0.0, fraction));
  const std::size_t keep =
      std::max<std::size_t>(1, static_cast<std::size_t>(std::floor(d->size() * fraction)));
  if (keep < d->size()) std::nth_element(d->begin(), d->begin() + (keep - 1), d->end());
  double sum = 0;
  for (std::size_t i = 0; i < keep; ++i) sum += (*d)[i];
  return sum / static_cast<double>(keep);
}

double trimmedClosestPoint(const KdTree& reference, const PointVector& cloud, double fraction,
                           std::vector<float>* scratch) {
  if (cloud.empty() || reference.empty()) return std::numeric_limits<double>::infinity();
  scratch->resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    float d2 = 0;
    reference.nearest(cloud[i], &d2);
    (*scratch)[i] = d2;
  }
  return trimmedMean(scratch, fraction);
}

double trimmedClosestPoint(const KdTree& reference, const PointVector& cloud, double fraction) {
  std::vector<float> scratch;
  return trimmedClosestPoint(reference, cloud, fraction, &scratch);
}

void HeightGrid::build(const PointVector& reference, double bin) {
  bin_ = bin;
  nx_ = ny_ = 0;
  mean_.clear();
  count_.clear();
  if (reference.empty() || !(bin > 0)) return;
  int ix1 = std::numeric_limits<int>::min(), iy1 = ix1;
  ix0_ = iy0_ = std::numeric_limits<int>::max();
  for (const Eigen::Vector3f& p : reference) {
    const int ix = static_cast<int>(std::floor(p.x() / bin_));
    const int iy = static_cast<int>(std::floor(p.y() / bin_));
    ix0_ = std::min(ix0_, ix);
    iy0_ = std::min(iy0_, iy);
    ix1 = std::max(ix1, ix);
    iy1 = std::max(iy1, iy);
  }
  const long nx = static_cast<long>(ix1) - ix0_ + 1, ny = static_cast<long>(iy1) - iy0_ + 1;
  if (nx * ny > 50'000'000L) return;
  nx_ = nx;
  ny_ = ny;
  mean_.assign(static_cast<std::size_t>(nx_ * ny_), 0.0);
  count_.assign(mean_.size(), 0);
  for (const Eigen::Vector3f& p : reference) {
    const long c = (static_cast<long>(std::floor(p.y() / bin_)) - iy0_) * nx_ +
                   (static_cast<long>(std::floor(p.x() / bin_)) - ix0_);
    mean_[c] += p.z();
    ++count_[c];
  }
  for (std::size_t c = 0; c < mean_.size(); ++c) {
    if (count_[c] > 0) mean_[c] /= count_[c];
  }
}

double HeightGrid::error(const PointVector& target, int min_points) const {
  if (nx_ == 0) return std::numeric_limits<double>::infinity();
  sum_.assign(mean_.size(), 0.0);
  tcount_.assign(mean_.size(), 0);
  for (const Eigen::Vector3f& p : target) {
    const long cx = static_cast<long>(std::floor(p.x() / bin_)) - ix0_;
    const long cy = static_cast<long>(std::floor(p.y() / bin_)) - iy0_;
    if (cx < 0 || cy < 0 || cx >= nx_ || cy >= ny_) continue;
    const long c = cy * nx_ + cx;
    sum_[c] += p.z();
    ++tcount_[c];
  }
  double err = 0;
  long shared = 0;
  const int need = std::max(1, min_points);
  for (std::size_t c = 0; c < mean_.size(); ++c) {
    if (count_[c] < need || tcount_[c] < need) continue;
    const double d = sum_[c] / tcount_[c] - mean_[c];
    err += d * d;
    ++shared;
  }
  return shared == 0 ? std::numeric_limits<double>::infinity() : err / shared;
}

}  // namespace calibration
}  // namespace ladar_perception
