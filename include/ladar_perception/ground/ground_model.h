// Ground models selectable by name (ground_segment --method, the nodelets' `method` parameter).
// One virtual call per scan, none per point.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ladar_perception/cloud/lidar_models.h"
#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"

namespace ladar_perception {

// The range gate of the ground models that fit the whole scan (plane fit, Hough columns): a
// return takes part when its range from the sensor is finite and within [min_range, max_range].
struct RangeGate {
  RangeGate(float min_range, float max_range)
      : min2(min_range * min_range), max2(max_range * max_range) {}
  bool admits(const Eigen::Vector3f& p) const {
    const float d2 = p.squaredNorm();
    return std::isfinite(d2) && d2 >= min2 && d2 <= max2;
  }
  float min2, max2;
};

class GroundModel {
 public:
  virtual ~GroundModel() = default;
  virtual std::string name() const = 0;
  // Labels every point of the view (out is resized to view.size(), same order as the input).
  // Never throws on bad data: NaN/Inf or out-of-range returns are labelled unknown.
  virtual void classify(const PointCloudView& view, const SensorPose& pose,
                        GroundClassification* out) = 0;
  // The sensor the clouds come from (lidar_models.h): models that read the beam geometry
  // (rows from elevations, the spacing of adjacent beams) take it from here; the others
  // ignore it. The HDL-64E until set.
  virtual void setLidarModel(const LidarModel& lidar) { (void)lidar; }
};

// Names accepted by makeGroundModel, the default first.
std::vector<std::string> groundModelNames();
// nullptr with a reason in *error for an unknown name.
std::unique_ptr<GroundModel> makeGroundModel(const std::string& name, std::string* error);

}  // namespace ladar_perception
