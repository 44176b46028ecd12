// Ray-traced sensor scans (thesis 4.2.1): every ray of a sensor model is cast onto the World
// from the sensor's pose; returns carry the class of the surface they hit (the ground truth),
// kept in a separate array so the algorithms never read it by accident.
//
// Range noise: Gaussian with the model's noise_sigma along the beam, counter-based (ray k of a
// scan with seed s always gets the same noise). Ranges are cast up to max_range; a return is
// kept when its noisy range lies in [min_range, max_range].
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/sim/sensor_models.h"
#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace sim {

struct SimulatedScan {
  PackedCloud cloud;           // returns only, in the sensor frame
  std::vector<uint8_t> truth;  // truth[i] = SurfaceClass of point i
};

// One revolution in the SENSOR frame, velodyneXYZIRTLayout (x, y, z, intensity, ring, time),
// only returns (no-hit rays omitted). Points are ordered by firing (azimuth step, then ring);
// `time` is seconds since the revolution's first firing. Reuse *out across scans: its buffers
// keep their capacity.
void simulateVelodyneRevolution(const World& world, const Eigen::Isometry3d& sensor_in_world,
                                const VelodyneModel& model, uint64_t seed, SimulatedScan* out);

// The same with the sensor moving during the revolution: the pose is interpolated from
// start to end over the firings and each point is in the sensor frame at its own firing time,
// as a real driver outputs it (motion distortion included).
void simulateVelodyneRevolution(const World& world, const Eigen::Isometry3d& sensor_at_start,
                                const Eigen::Isometry3d& sensor_at_end, const VelodyneModel& model,
                                uint64_t seed, SimulatedScan* out);

// One 2D scan in sensor_msgs/LaserScan terms, plus the returns as a cloud.
struct SimulatedLaserScan {
  float angle_min = 0.f, angle_max = 0.f, angle_increment = 0.f;
  float time_increment = 0.f, scan_time = 0.f;
  float range_min = 0.f, range_max = 0.f;
  std::vector<float> ranges;       // per beam; +Inf when there is no return in range (REP 117)
  std::vector<float> intensities;  // per beam, 0 without a return
  std::vector<uint8_t> beam_truth; // per beam SurfaceClass, kNone without a return
  SimulatedScan points;            // returns only: xyziLayout in the sensor frame + truth
};
void simulateSickScan(const World& world, const Eigen::Isometry3d& sensor_in_world,
                      const SickModel& model, uint64_t seed, SimulatedLaserScan* out);

// One stereo depth frame: returns only, x, y, z float32 in the sensor frame (x forward).
void simulateStereoFrame(const World& world, const Eigen::Isometry3d& sensor_in_world,
                         const StereoModel& model, uint64_t seed, SimulatedScan* out);

// The simulated intensity of a return (0..255): a per-class reflectivity scaled by the cosine
// of the incidence angle.
float returnIntensity(SurfaceClass c, float cos_incidence);

}  // namespace sim
}  // namespace ladar_perception
