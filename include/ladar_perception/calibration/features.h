// Features (Algorithm 4, thesis 4.6.2): the points are binned into a horizontal x-y grid of
// `bin` metres (the feature bin); per bin the point of maximum height is a local maximum and the
// point of minimum height a local minimum. Bins of 2-4 m worked best in the thesis.
#pragma once

#include <cstdint>
#include <vector>

#include "ladar_perception/calibration/accumulation.h"

namespace ladar_perception {
namespace calibration {

struct FeatureSet {
  PointVector maxima;  // one per occupied bin
  PointVector minima;  // one per occupied bin, same bin order as maxima
  void clear() {
    maxima.clear();
    minima.clear();
  }
};

// Reuses its grid between calls, so extracting features per hypothesis does not allocate once
// the buffers have grown. Bins are anchored at the odom origin (bin i covers [i*bin, (i+1)*bin)).
class FeatureExtractor {
 public:
  explicit FeatureExtractor(double bin_size = 3.0) : bin_(bin_size) {}
  double binSize() const { return bin_; }
  void setBinSize(double bin_size) { bin_ = bin_size; }
  // Bins holding fewer than min_points points give no feature (1 = every occupied bin).
  void extract(const PointVector& points, FeatureSet* out, int min_points = 1);

 private:
  double bin_;
  std::vector<int32_t> max_index_, min_index_, count_;
};

// Convenience for tests and one-off use.
FeatureSet extractFeatures(const PointVector& points, double bin_size);

}  // namespace calibration
}  // namespace ladar_perception
