// What every ground model returns: a label and P(obstacle) per input point, in input order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

namespace ladar_perception {

// Labels of the `classified` output (interfaces.md).
enum Label : uint8_t {
  kLabelGround = 0,
  kLabelObstacle = 1,
  kLabelUnknown = 2,  // not evaluated: NaN/Inf return, out of range, no ground estimate
};

// Per-point result, indexed like the input cloud. Keep one instance per stream and reuse it:
// resize() keeps the capacity, so steady-state scans do not allocate.
struct GroundClassification {
  std::vector<uint8_t> labels;
  std::vector<float> p_obstacle;

  void resize(std::size_t n) {
    labels.resize(n);
    p_obstacle.resize(n);
  }
  std::size_t size() const { return labels.size(); }
  std::size_t count(Label label) const {
    std::size_t c = 0;
    for (uint8_t l : labels) c += (l == label);
    return c;
  }
};

// Where the sensor is relative to the local ground. The ground frame is gravity aligned
// (z up), its origin is the ground point directly under the sensor, so a return on flat ground
// has Height 0 (algorithms.md conventions). From tf in the nodelets, from --sensor-height in
// the tools.
struct SensorPose {
  Eigen::Isometry3f sensor_to_ground = Eigen::Isometry3f::Identity();

  static SensorPose fromHeight(float sensor_height) {
    SensorPose p;
    p.sensor_to_ground.translation() = Eigen::Vector3f(0.f, 0.f, sensor_height);
    return p;
  }
  float height() const { return sensor_to_ground.translation().z(); }
};

}  // namespace ladar_perception
