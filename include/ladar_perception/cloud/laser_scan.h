// A 2D ladar scan (the geometry of sensor_msgs/LaserScan) and its projection to points, ROS-free.
// The ROS adapter borrows the message's arrays into a LaserScanView; nothing is copied.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ladar_perception/cloud/point_cloud_view.h"

namespace ladar_perception {

// Borrowed view of one scan: return k is at angle angle_min + k * angle_increment (radians,
// counter-clockwise about the sensor's z axis from its x axis) in the sensor's x-y plane.
struct LaserScanView {
  float angle_min = 0.f;
  float angle_increment = 0.f;
  float range_min = 0.f;
  float range_max = 0.f;
  const float* ranges = nullptr;
  std::size_t size = 0;
  const float* intensities = nullptr;  // nullptr, or `size` values
};

// False with a one-sentence reason when the scan's geometry cannot be used (non-finite or zero
// angle_increment, a sweep over more than one turn, range_min/range_max not finite or not
// increasing, too many returns). A scan with no returns is valid.
bool validateLaserScan(const LaserScanView& scan, std::string* error);

// True when return k is a measurement: finite and inside [range_min, range_max]. NaN, +-Inf
// (the REP-117 "no return" values) and out-of-range readings are not.
inline bool validReturn(const LaserScanView& scan, std::size_t k) {
  const float r = scan.ranges[k];
  return r >= scan.range_min && r <= scan.range_max;  // false for NaN; +-Inf fail one side
}

// Projects scans to sensor-frame points (z = 0). Caches the cos/sin table of the last scan
// geometry, so a stream of scans of one sensor computes no trigonometry per scan and does not
// allocate once warm. Keep one per stream.
class LaserScanProjector {
 public:
  // x, y of every return (NaN for invalid returns, so indices match the scan); `x` and `y` are
  // arrays of scan.size floats. Returns the number of valid returns.
  std::size_t project(const LaserScanView& scan, float* x, float* y);

  // The scan as a packed cloud of laserScanLayout(): one point per return in scan order
  // (organised, width = scan.size), invalid returns as NaN points, intensity 0 when the scan
  // has none. `data` must hold scan.size * laserScanLayout(..).point_step bytes.
  std::size_t projectPacked(const LaserScanView& scan, uint8_t* data);

 private:
  void updateTable(const LaserScanView& scan);
  std::vector<float> cos_, sin_;
  float angle_min_ = 0.f, angle_increment_ = 0.f;
};

// x, y, z, intensity float32 (16 bytes per point), the layout of a projected scan.
CloudLayout laserScanLayout(uint32_t num_points);

}  // namespace ladar_perception
