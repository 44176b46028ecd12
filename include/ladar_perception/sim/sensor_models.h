// Sensor models of the simulator with the thesis's Table 4.1 defaults. Every field is a plain
// parameter; noise_sigma = 0 gives noise-free scans.
#pragma once

#include <string>
#include <vector>

#include "ladar_perception/cloud/lidar_models.h"

namespace ladar_perception {
namespace sim {

// Named range-noise profiles.
//  "table4.1": the thesis's Table 4.1 accuracies (Velodyne 0.2 m, SICK 0.1 m, stereo 0.5 m),
//              the default, as the thesis's calibration experiment used them;
//  "datasheet": manufacturers' figures (HDL-64E < 2 cm -> 0.02 m; LMS-291 +-35 mm systematic,
//              1 sigma ~ 0.01 m; stereo unchanged), the realistic profile ground extraction is
//              evaluated with;
//  "none": noise free.
enum class NoiseProfile { kTable41, kDatasheet, kNone };
bool noiseProfileFromName(const std::string& name, NoiseProfile* profile);
const char* noiseProfileName(NoiseProfile profile);

// The 64 laser elevations of an HDL-64E in degrees, ring order (ring 0 = lowest laser, -24.8;
// ring 63 = highest, +2.0): the package's one table, cloud/laser_elevations.h.
const std::vector<float>& hdl64eElevationsDeg();

// A spinning multi-laser ladar (Velodyne HDL-64E by default).
struct VelodyneModel {
  std::vector<float> elevations_deg;  // ring order (ascending)
  int azimuth_steps = 1800;           // firings per revolution per laser
  double rate_hz = 10.0;              // revolutions per second
  double min_range = 2.0;             // Table 4.1
  double max_range = 60.0;            // Table 4.1 (the unit reaches 120 m)
  double noise_sigma = 0.2;           // Table 4.1 accuracy, metres (1 sigma, along the beam)
  // Azimuth of the first firing of a revolution (radians, sensor frame); the head spins
  // clockwise seen from above (azimuth decreasing), as the real unit does. Starting behind
  // the vehicle puts the revolution's seam there.
  double start_azimuth = 3.141592653589793;
  // Organised output as Ouster's driver publishes it (ousterLayout: one row per laser, the
  // top laser first, every firing a slot, empty slots zero) instead of the returns only.
  bool organised = false;

  static VelodyneModel hdl64e(NoiseProfile profile = NoiseProfile::kTable41);
  // A model of the lidar table (cloud/lidar_models.h): its beams, firings, rate, range limits
  // and organisation; noise: the datasheet's with kDatasheet and kTable41 (Table 4.1 has the
  // HDL-64E only), none with kNone. "hdl64e" is hdl64e(profile) (Table 4.1 ranges).
  static VelodyneModel fromLidarModel(const LidarModel& lidar, NoiseProfile profile);
  // The same by name; false with the known names in *error for an unknown one.
  static bool named(const std::string& name, NoiseProfile profile, VelodyneModel* model,
                    std::string* error);
  int lasers() const { return static_cast<int>(elevations_deg.size()); }
  double period() const { return 1.0 / rate_hz; }
  std::size_t raysPerRevolution() const {
    return static_cast<std::size_t>(lasers()) * static_cast<std::size_t>(azimuth_steps);
  }
  // A clear reason when the model cannot be simulated, empty when valid.
  std::string validate() const;
};

// A 2D scanning ladar (SICK LMS-291): beams in the sensor's x-y plane from angle_min to
// angle_max, counter-clockwise (sensor_msgs/LaserScan conventions). Tilting and vertical
// mounting come from the mount pose.
struct SickModel {
  double angle_min = -1.5707963267948966;  // 180 degrees
  double angle_max = 1.5707963267948966;
  double angle_increment = 0.008726646259971648;  // 0.5 degree -> 361 beams
  double rate_hz = 75.0;
  double min_range = 0.5;
  double max_range = 80.0;
  double noise_sigma = 0.1;  // Table 4.1

  static SickModel lms291(NoiseProfile profile = NoiseProfile::kTable41);
  int beams() const;
  std::string validate() const;
};

// A stereo camera giving a depth cloud: a pinhole grid of `columns` x `rows` rays over the
// field of view, looking along the sensor's +x (body frame: x forward, y left, z up; not
// the optical frame), 2-12 m. Depth comes from disparity, d = f b / depth (f the focal length
// of the image_columns-wide disparity image in pixels, b the baseline), so the matcher's
// disparity error makes the depth error grow with depth squared:
// sigma_depth = depth^2 sigma_d / (f b). noise_sigma is that depth error at max_range (Table
// 4.1's 0.5 m for the stereo camera, read as its worst case); sigma_d follows from it. The
// disparity is then rounded to the matcher's sub-pixel step, and the point moved along its ray.
struct StereoModel {
  double horizontal_fov = 1.2217304763960306;  // 70 degrees
  double vertical_fov = 0.9599310885968813;     // 55 degrees
  int columns = 160;
  int rows = 120;
  double rate_hz = 10.0;
  double min_range = 2.0;
  double max_range = 12.0;
  double noise_sigma = 0.5;         // depth error at max_range [m] (1 sigma)
  double baseline = 0.12;           // [m] (Bumblebee2)
  int image_columns = 640;          // the disparity image's width [pixels]
  double disparity_step_px = 0.125; // the matcher's sub-pixel step (0 = not rounded)

  double focalPixels() const;       // f of the disparity image
  double disparitySigma() const;    // sigma_d [pixels]
  // The depth error (1 sigma) at `depth` metres.
  double depthSigma(double depth) const;

  static StereoModel bumblebee(NoiseProfile profile = NoiseProfile::kTable41);
  std::string validate() const;
};

}  // namespace sim
}  // namespace ladar_perception
