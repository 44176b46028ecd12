// Error metrics between a reference and a target cloud (thesis 4.5).
#pragma once

#include <limits>
#include <vector>

#include "ladar_perception/calibration/accumulation.h"
#include "ladar_perception/calibration/kdtree.h"

namespace ladar_perception {
namespace calibration {

// Trimmed closest point (eq 4.1): for each point i of `cloud`, d_i^2 is the squared distance to
// the closest point of the reference (the KD-tree, built once per reference cloud); sorted
// ascending, the error is the mean of the smallest N * fraction of them, so part of the data may
// fail to overlap without penalty. Infinity when `cloud` is empty. `scratch` avoids allocation.
double trimmedClosestPoint(const KdTree& reference, const PointVector& cloud, double fraction,
                           std::vector<float>* scratch);
double trimmedClosestPoint(const KdTree& reference, const PointVector& cloud, double fraction);

// The trimmed mean of already computed squared distances (the second half of eq 4.1); reorders
// `sq_dists`.
double trimmedMean(std::vector<float>* sq_dists, double fraction);

// Average height in grid (4.5.2): both clouds are binned into the same x-y grid of `bin` metres;
// the error is the mean squared difference of the mean heights over the bins both occupy.
class HeightGrid {
 public:
  // Builds the reference's grid (bins anchored at the odom origin, over its bounding box).
  void build(const PointVector& reference, double bin);
  bool empty() const { return nx_ == 0; }
  // Infinity when no bin is shared. min_points: bins with fewer points on either side are skipped.
  double error(const PointVector& target, int min_points = 1) const;

 private:
  double bin_ = 1.0;
  int ix0_ = 0, iy0_ = 0;
  long nx_ = 0, ny_ = 0;
  std::vector<double> mean_;
  std::vector<int> count_;
  mutable std::vector<double> sum_;  // per-call scratch
  mutable std::vector<int> tcount_;
};

}  // namespace calibration
}  // namespace ladar_perception
