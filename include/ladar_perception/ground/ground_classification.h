// What every ground model returns: a label and P(obstacle) per input point, in input order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace ladar_perception {

// Labels of the `classified` output (interfaces.md).
enum Label : uint8_t {
  kLabelGround = 0,
  kLabelObstacle = 1,
  kLabelUnknown = 2,  // not evaluated: NaN/Inf return, out of range, no ground estimate
};

// An allocator whose construct() without a value default-initialises: resize() of a vector of
// bytes or floats then leaves the new elements unwritten instead of zero-filling them.
template <typename T, typename Base = std::allocator<T>>
class DefaultInitAllocator : public Base {
  using Traits = std::allocator_traits<Base>;

 public:
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;
  };
  using Base::Base;
  DefaultInitAllocator() = default;
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    Traits::construct(static_cast<Base&>(*this), p, std::forward<Args>(args)...);
  }
};

// Per-point result, indexed like the input cloud. Keep one instance per stream and reuse it:
// resize() keeps the capacity, so steady-state scans do not allocate. resize() does not
// initialise new elements: every ground model writes the label and P(obstacle) of every
// point it is given (unknown and 0 where it cannot evaluate one).
struct GroundClassification {
  std::vector<uint8_t, DefaultInitAllocator<uint8_t>> labels;
  std::vector<float, DefaultInitAllocator<float>> p_obstacle;

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
  // A tilted mount: the sensor sensor_height above the ground, rolled about its x axis and
  // pitched about its y axis (degrees; positive pitch turns the sensor's x axis downward,
  // R = Ry(pitch) Rx(roll), as a tf of rpy (roll, pitch, 0)).
  static SensorPose fromMount(float sensor_height, float roll_deg, float pitch_deg) {
    SensorPose p = fromHeight(sensor_height);
    const float deg = 3.14159265358979f / 180.f;
    p.sensor_to_ground.linear() =
        (Eigen::AngleAxisf(pitch_deg * deg, Eigen::Vector3f::UnitY()) *
         Eigen::AngleAxisf(roll_deg * deg, Eigen::Vector3f::UnitX())).toRotationMatrix();
    return p;
  }
  float height() const { return sensor_to_ground.translation().z(); }
};

}  // namespace ladar_perception
