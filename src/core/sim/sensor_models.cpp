#include "ladar_perception/sim/sensor_models.h"

#include <cmath>

#include "ladar_perception/cloud/laser_elevations.h"

namespace ladar_perception {
namespace sim {

bool noiseProfileFromName(const std::string& name, NoiseProfile* profile) {
  if (name == "table4.1" || name == "thesis") *profile = NoiseProfile::kTable41;
  else if (name == "datasheet" || name == "realistic") *profile = NoiseProfile::kDatasheet;
  else if (name == "none") *profile = NoiseProfile::kNone;
  else return false;
  return true;
}

const char* noiseProfileName(NoiseProfile profile) {
  switch (profile) {
    case NoiseProfile::kTable41: return "table4.1";
    case NoiseProfile::kDatasheet: return "datasheet";
    case NoiseProfile::kNone: return "none";
  }
  return "table4.1";
}

const std::vector<float>& hdl64eElevationsDeg() {
  return ::ladar_perception::hdl64eElevationsDeg();  // the package's one HDL-64E table
}

VelodyneModel VelodyneModel::hdl64e(NoiseProfile profile) {
  VelodyneModel m;
  m.elevations_deg = hdl64eElevationsDeg();
  m.noise_sigma = profile == NoiseProfile::kTable41 ? 0.2
                  : profile == NoiseProfile::kDatasheet ? 0.02 : 0.0;
  return m;
}

VelodyneModel VelodyneModel::fromLidarModel(const LidarModel& lidar, NoiseProfile profile) {
  if (lidar.name == "hdl64e") return hdl64e(profile);
  VelodyneModel m;
  m.elevations_deg = lidar.elevations_deg;
  m.azimuth_steps = lidar.azimuth_steps;
  m.rate_hz = lidar.rate_hz;
  m.min_range = lidar.min_range;
  m.max_range = lidar.max_range;
  m.noise_sigma = profile == NoiseProfile::kNone ? 0.0 : lidar.noise_sigma;
  m.organised = lidar.organised;
  return m;
}

bool VelodyneModel::named(const std::string& name, NoiseProfile profile, VelodyneModel* model,
                          std::string* error) {
  const LidarModel* lidar = findLidarModel(name);
  if (!lidar) {
    if (error) *error = "unknown sensor " + name + " (known: " + lidarModelNames() + ")";
    return false;
  }
  *model = fromLidarModel(*lidar, profile);
  return true;
}

std::string VelodyneModel::validate() const {
  if (elevations_deg.empty()) return "velodyne model has no lasers";
  if (elevations_deg.size() > 65535) return "velodyne model has more lasers than a ring can number";
  if (organised && elevations_deg.size() > 128) return "an organised model has at most 128 lasers";
  for (float e : elevations_deg) {
    if (!std::isfinite(e) || std::abs(e) >= 90.f) return "velodyne laser elevation outside (-90, 90) degrees";
  }
  if (azimuth_steps < 1 || azimuth_steps > 100000) return "velodyne azimuth_steps must be 1..100000";
  if (!(rate_hz > 0.0)) return "velodyne rate_hz must be positive";
  if (!(min_range >= 0.0) || !(max_range > min_range)) return "velodyne needs 0 <= min_range < max_range";
  if (!(noise_sigma >= 0.0)) return "velodyne noise_sigma must be >= 0";
  return "";
}

SickModel SickModel::lms291(NoiseProfile profile) {
  SickModel m;
  m.noise_sigma = profile == NoiseProfile::kTable41 ? 0.1
                  : profile == NoiseProfile::kDatasheet ? 0.01 : 0.0;
  return m;
}

int SickModel::beams() const {
  if (!(angle_increment > 0.0) || !(angle_max >= angle_min)) return 0;
  return static_cast<int>(std::floor((angle_max - angle_min) / angle_increment + 1e-6)) + 1;
}

std::string SickModel::validate() const {
  if (!(angle_increment > 0.0) || !(angle_max >= angle_min)) return "sick needs angle_increment > 0 and angle_max >= angle_min";
  if (beams() > 100000) return "sick has too many beams";
  if (!(rate_hz > 0.0)) return "sick rate_hz must be positive";
  if (!(min_range >= 0.0) || !(max_range > min_range)) return "sick needs 0 <= min_range < max_range";
  if (!(noise_sigma >= 0.0)) return "sick noise_sigma must be >= 0";
  return "";
}

StereoModel StereoModel::bumblebee(NoiseProfile profile) {
  StereoModel m;
  m.noise_sigma = profile == NoiseProfile::kNone ? 0.0 : 0.5;
  return m;
}

double StereoModel::focalPixels() const {
  return 0.5 * image_columns / std::tan(0.5 * horizontal_fov);
}

double StereoModel::disparitySigma() const {
  return noise_sigma * focalPixels() * baseline / (max_range * max_range);
}

double StereoModel::depthSigma(double depth) const {
  return depth * depth * disparitySigma() / (focalPixels() * baseline);
}

std::string StereoModel::validate() const {
  if (columns < 1 || rows < 1 || columns * static_cast<long>(rows) > 4000000) return "stereo needs 1..4e6 pixels";
  if (!(horizontal_fov > 0.0 && horizontal_fov < 3.1) || !(vertical_fov > 0.0 && vertical_fov < 3.1)) {
    return "stereo field of view must be in (0, 3.1) radians";
  }
  if (!(rate_hz > 0.0)) return "stereo rate_hz must be positive";
  if (!(min_range >= 0.0) || !(max_range > min_range)) return "stereo needs 0 <= min_range < max_range";
  if (!(noise_sigma >= 0.0)) return "stereo noise_sigma must be >= 0";
  if (!(baseline > 0.0) || image_columns < 1) return "stereo needs baseline > 0 and image_columns >= 1";
  if (!(disparity_step_px >= 0.0)) return "stereo disparity_step_px must be >= 0";
  return "";
}

}  // namespace sim
}  // namespace ladar_perception
